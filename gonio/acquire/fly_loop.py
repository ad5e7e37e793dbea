"""The engine's loop for a fly plan: sweep after sweep (docs/explanations/acquisition.md).

`FlyLoop`, a base class of `gonio.acquire.engine.Engine`, which runs it in place of the
stop-and-go loop when the plan has sweeps. Each sweep with a target still to measure is
measured whole (`gonio.acquire.sweep.run_sweep`), a health check and a calibration
before it when due; its streams are merged (`gonio.acquire.sweep.derive`) and committed
with its samples and the targets it did not read in one transaction (`_commit_sweep`).
A fault abandons the sweep (journaled, its raw streams with it) and follows the plan's
``acquisition.on_fault``: retried, its targets skipped, or the session ended.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from drivers.devices import Devices
from drivers.errors import CommError, DetectorError, DriverError, MotionTimeout, MotorFault
from drivers.stream import StreamReading
from gonio.acquire.ending import EndSession
from gonio.acquire.progress import Observer
from gonio.acquire.recovery import MotorRecovery
from gonio.acquire.runtime import RunTime
from gonio.acquire.signals import StopRequests
from gonio.acquire.sweep import RawSweep, derive, run_sweep
from gonio.planner.model import Plan
from gonio.planner.policies import AcquisitionSpec
from gonio.rig.model import Rig
from gonio.store.journal import Journal
from gonio.types import FloatArray


class FlyLoop:
    """The fly loop of `gonio.acquire.engine.Engine` (a base class of it): `_fly`
    measures the sweeps of a fly plan, on the engine's devices, into its journal."""

    # The engine's, set when it is made (`Engine`):
    plan: Plan
    devices: Devices
    journal: Journal
    time: RunTime
    progress: Observer
    stops: StopRequests
    move_timeout_s: float
    spec: AcquisitionSpec
    rig: Rig
    axes: tuple[str, ...]
    _busy_until: float
    _current: int | None
    _recovery: MotorRecovery

    if TYPE_CHECKING:  # the engine's machinery the loop uses (`Engine`)

        def _between_targets(self) -> None: ...
        def _obey(self) -> None: ...
        def _closing(self, measuring: bool) -> None: ...
        def _within_limits(self, pose: np.ndarray) -> str | None: ...
        def _skip(self, i: int, reason: str) -> None: ...
        def _hold_all(self) -> None: ...
        def _event(self, kind: str, data: Mapping[str, Any], target: int | None = None) -> None: ...
        def _sim(self) -> dict[str, Any]: ...
        @staticmethod
        def _fault_data(exc: DriverError) -> dict[str, Any]: ...
        def _write_sample(
            self, i: int, attempts: int, angles: list[float], settled_s: float,
            state: Mapping[str, Any], **measured: Any,
        ) -> None: ...  # fmt: skip

    def _fly(self, todo: np.ndarray) -> None:
        """Each sweep with a target still to measure, whole (`gonio.acquire.sweep`);
        a health check and a calibration before it when due."""
        sweeps = self.plan.sweeps
        assert sweeps is not None
        left = np.zeros(len(self.plan), dtype=np.bool_)
        left[todo] = True
        ks = [
            k for k in range(len(sweeps))
            if left[int(sweeps.first[k]) : int(sweeps.first[k] + sweeps.count[k])].any()
        ]  # fmt: skip
        self.progress.start(self.plan, todo)
        done = 0
        for k in ks:
            self._between_targets()
            done += self._sweep(k)
            self.progress.advance(min(done, len(todo)))
            self.stops.raise_if_requested()
            self._obey()
        self._closing(bool(ks))

    def _sweep(self, k: int) -> int:
        """Measure sweep ``k`` and commit it in one transaction; the targets it
        finished (measured or skipped). Faults follow the plan's ``on_fault``: the
        sweep is journaled as abandoned (its raw streams with it), then retried,
        skipped or the run ended (a motor fault: resumable, the sweep redone)."""
        sweeps = self.plan.sweeps
        assert sweeps is not None
        first, count = int(sweeps.first[k]), int(sweeps.count[k])
        targets = range(first, first + count)
        self._current = first
        for name in ("start", "stop"):
            refused = self._within_limits(getattr(sweeps, name)[k])
            if refused is not None:
                with self.journal.transaction():
                    for i in targets:
                        self._skip(i, f"sweep {k}: {refused}")
                return count
        on_fault = self.spec.on_fault
        simulation = self.devices.simulation
        for attempt in range(on_fault.retries + 1):
            if simulation is not None:
                simulation.begin_sample(first)
            began = self.time.now()
            # About the sweep's length (its readings; a move, settle and ramps besides):
            # a first Ctrl-C lets a short sweep finish, abandons a long one.
            self._busy_until = began + int(sweeps.streamed[k]) * sweeps.period_s + 2.0
            try:
                raw = self._recovery.attempt(
                    lambda: run_sweep(
                        self.devices, self.axes, sweeps, k,
                        settle_s=self.rig.spec.settle_s, timeout_s=self.move_timeout_s,
                    ),
                    target=first,
                )  # fmt: skip
                break
            except DriverError as exc:
                self._hold_all()
                data = {**self._fault_data(exc), "attempt": attempt + 1}
                with self.journal.transaction():
                    self.journal.sweep(k, "abandoned", began, self.time.now(), data, [], [])
                if isinstance(exc, MotorFault | MotionTimeout) or not isinstance(
                    exc, CommError | DetectorError
                ):
                    raise
                if attempt < on_fault.retries:
                    self._event("retry", {**data, **self._sim()}, target=first)
                    continue
                if on_fault.then == "skip":
                    with self.journal.transaction():
                        for i in targets:
                            self._skip(i, f"sweep {k}: {type(exc).__name__}: {exc}")
                    return count
                self._event("fault", data, target=first)
                raise EndSession("aborted", f"sweep {k}: {exc}") from None
        self._commit_sweep(k, attempt + 1, raw)
        return count

    def _commit_sweep(self, k: int, attempts: int, raw: RawSweep) -> None:
        """Merge the sweep's streams and journal it, its raw streams, its samples and
        the targets it did not read (skipped), in one transaction."""
        sweeps = self.plan.sweeps
        assert sweeps is not None
        offset = self.time.offset
        d = derive(raw, self.axes, sweeps, self.plan.arrival_s, k)
        merged, extra = d.samples, d.extra
        request, reply, positions = d.request, d.reply, d.positions
        first, count = int(sweeps.first[k]), int(sweeps.count[k])
        state = self._sim()
        last = int(np.argmax(d.ended[merged.index])) if len(merged.index) else -1
        data = {
            "first": first, "count": count, "readings": len(raw.readings),
            "matched": len(d.matched.index), "kept": len(merged.index), "polls": len(raw.polls),
            "attempts": attempts,
        }  # fmt: skip
        polls = [
            (a + offset, b + offset, p)
            for a, b, p in zip(request.tolist(), reply.tolist(), positions.tolist(), strict=True)
        ]
        stream = [
            (
                r.started_s + offset, r.ended_s + offset, r.value,
                r.std if math.isfinite(r.std) else None, int(r.saturated),
                r.device_t_s, None if r.received_s is None else r.received_s + offset,
            )
            for r in raw.readings
        ]  # fmt: skip
        read = set(merged.target.tolist())
        with self.journal.transaction():
            self.journal.sweep(
                k, "measured", raw.started_s + offset, raw.ended_s + offset, data, polls, stream
            )
            for n, r in enumerate(merged.index.tolist()):
                reading = raw.readings[r]
                i = int(merged.target[n])
                self._fly_sample(
                    i, attempts, raw.started_s, merged.angles[n], reading,
                    float(merged.smear[n]), float(merged.timing[n]), float(extra[n]),
                    state if n == last else {},
                )  # fmt: skip
            for i in range(first, first + count):
                if i not in read:
                    self._skip(i, f"sweep {k}: no reading in the constant-velocity part")

    def _fly_sample(
        self, i: int, attempts: int, settled_s: float, angles: FloatArray,
        reading: StreamReading, smear: float, timing: float, extra: float,
        state: Mapping[str, Any],
    ) -> None:  # fmt: skip
        std = reading.std if math.isfinite(reading.std) else 0.0
        offset = self.time.offset
        self._write_sample(
            i, attempts, angles.tolist(), settled_s + offset, state,
            exposure_s=reading.ended_s - reading.started_s, averages=1, n=1,
            counts=reading.value, counts_std=math.hypot(std, extra),
            saturated=int(reading.saturated), remeasured=0,
            started_s=reading.started_s + offset, ended_s=reading.ended_s + offset,
            smear_rad=smear, timing_rad=timing,
        )  # fmt: skip
