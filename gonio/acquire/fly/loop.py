"""The fly loop: a fly plan's sweeps measured one after another
(docs/explanations/acquisition.md).

`FlyLoop`, held by `gonio.acquire.engine.Engine`, which runs it in place of the
stop-and-go loop when the plan has sweeps; it sees the engine through a `FlyContext`.
Each sweep with a target still to measure is measured whole
(`gonio.acquire.fly.run.run_sweep`), a health check and a calibration before it when
due; its streams are merged (`gonio.acquire.fly.merge.derive`) and committed with its
samples and the targets it did not read in one transaction (`FlyLoop._commit_sweep`).
A fault abandons the sweep (journaled, its raw streams with it) and follows the plan's
``acquisition.on_fault``: retried, its targets skipped, or the session ended.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from drivers.devices import Devices
from drivers.errors import CommError, DetectorError, DriverError, MotionTimeout, MotorFault
from drivers.stream import StreamReading
from gonio.acquire.ending import EndSession, fault_data
from gonio.acquire.fly.merge import Derived, RawSweep, derive
from gonio.acquire.fly.run import run_sweep
from gonio.acquire.observer import Observer
from gonio.acquire.recovery import MotorRecovery
from gonio.acquire.runtime import RunTime
from gonio.acquire.signals import StopRequests
from gonio.planner import AcquisitionSpec, Plan
from gonio.rig import Rig
from gonio.store import Journal
from gonio.types import FloatArray


class EventWriter(Protocol):
    """Journal an event of ``kind`` (about ``target``, if any)."""

    def __call__(self, kind: str, data: Mapping[str, Any], target: int | None = None) -> None: ...


class SampleWriter(Protocol):
    """Journal target ``i``'s sample read back at ``angles`` (`Engine._write_sample`)."""

    def __call__(
        self, i: int, attempts: int, angles: list[float], settled_s: float,
        state: Mapping[str, Any], **measured: Any,
    ) -> None: ...  # fmt: skip


@dataclass(frozen=True)
class FlyContext:
    """What the fly loop uses of the engine that holds it: the run's parts, and the
    engine's machinery as callables."""

    plan: Plan
    devices: Devices
    journal: Journal
    time: RunTime
    progress: Observer
    stops: StopRequests
    spec: AcquisitionSpec
    rig: Rig
    axes: tuple[str, ...]
    move_timeout_s: float
    recovery: MotorRecovery
    between_targets: Callable[[], None]  # a health check and a calibration when due
    obey: Callable[[], None]  # the control requests posted since the last step
    within_limits: Callable[[np.ndarray], str | None]  # why a pose must not be commanded
    skip: Callable[[int, str], None]  # journal a target skipped, and why
    hold_all: Callable[[], None]  # tell every axis to hold
    event: EventWriter
    sim_state: Callable[[], dict[str, Any]]  # ``{"sim_state": …}`` on a simulated backend
    write_sample: SampleWriter
    in_flight: Callable[[int], None]  # the target in flight (a motor fault names it)
    busy_until: Callable[[float], None]  # the run time the step in flight ends


#: A sweep is redone when it kept fewer of its targets than this many short of them…
SHORT_READINGS = 2
#: …and this share of them: a reading or two lost at a sweep's ends, as a rehearsal's
#: host timing loses every time, is not worth measuring the sweep again.
SHORT_SHARE = 0.01


def short_allowed(count: int) -> float:
    """How many of a sweep's ``count`` targets may go unread without redoing it."""
    return max(SHORT_READINGS, SHORT_SHARE * count)


@dataclass(frozen=True)
class FlyLoop:
    """Measures the sweeps of a fly plan, on the devices of ``context``, into its
    journal (see the module docstring)."""

    context: FlyContext

    def run(self, todo: np.ndarray) -> bool:
        """Each sweep with a target still to measure, whole; a health check and a
        calibration before it when due. Whether any sweep was measured (the engine's
        closing calibration is due then)."""
        c = self.context
        sweeps = c.plan.sweeps
        assert sweeps is not None
        left = np.zeros(len(c.plan), dtype=np.bool_)
        left[todo] = True
        ks = [
            k for k in range(len(sweeps))
            if left[int(sweeps.first[k]) : int(sweeps.first[k] + sweeps.count[k])].any()
        ]  # fmt: skip
        c.progress.start(c.plan, todo)
        done = 0
        for k in ks:
            c.between_targets()
            done += self._sweep(k)
            c.progress.advance(min(done, len(todo)))
            c.stops.raise_if_requested()
            c.obey()
        return bool(ks)

    def _sweep(self, k: int) -> int:
        """Measure sweep ``k`` and commit it in one transaction; the targets it
        finished (measured or skipped). Faults follow the plan's ``on_fault``: the
        sweep is journaled as abandoned (its raw streams with it), then retried,
        skipped or the run ended (a motor fault: resumable, the sweep redone)."""
        c = self.context
        sweeps = c.plan.sweeps
        assert sweeps is not None
        first, count = int(sweeps.first[k]), int(sweeps.count[k])
        targets = range(first, first + count)
        c.in_flight(first)
        for name in ("start", "stop"):
            refused = c.within_limits(getattr(sweeps, name)[k])
            if refused is not None:
                with c.journal.transaction():
                    for i in targets:
                        c.skip(i, f"sweep {k}: {refused}")
                return count
        on_fault = c.spec.on_fault
        simulation = c.devices.simulation
        for attempt in range(on_fault.retries + 1):
            if simulation is not None:
                simulation.begin_sample(first)
            began = c.time.now()
            # About the sweep's length (its readings; a move, settle and ramps besides):
            # a first Ctrl-C lets a short sweep finish, abandons a long one.
            c.busy_until(began + int(sweeps.streamed[k]) * sweeps.period_s + 2.0)
            try:
                raw = c.recovery.attempt(
                    lambda: run_sweep(
                        c.devices, c.axes, sweeps, k,
                        settle_s=c.rig.spec.settle_s, timeout_s=c.move_timeout_s,
                    ),
                    target=first,
                )  # fmt: skip
            except DriverError as exc:
                c.hold_all()
                data = {**fault_data(exc), "attempt": attempt + 1}
                with c.journal.transaction():
                    c.journal.sweep(k, "abandoned", began, c.time.now(), data, [], [])
                if isinstance(exc, MotorFault | MotionTimeout) or not isinstance(
                    exc, CommError | DetectorError
                ):
                    raise
                if attempt < on_fault.retries:
                    c.event("retry", {**data, **c.sim_state()}, target=first)
                    continue
                if on_fault.then == "skip":
                    with c.journal.transaction():
                        for i in targets:
                            c.skip(i, f"sweep {k}: {type(exc).__name__}: {exc}")
                    return count
                c.event("fault", data, target=first)
                raise EndSession("aborted", f"sweep {k}: {exc}") from None
            d = derive(raw, c.axes, sweeps, c.plan.arrival_s, k)
            kept = len(d.samples.index)
            if count - kept <= short_allowed(count) or attempt == on_fault.retries:
                break
            # Fewer readings than the plan asks (a host stall, a lost stream): redone.
            data = {"short": True, "kept": kept, "count": count, "attempt": attempt + 1}
            started, ended, polls, stream = self._raw_rows(raw, d)
            with c.journal.transaction():
                c.journal.sweep(k, "abandoned", started, ended, data, polls, stream)
            c.event("retry", {**data, **c.sim_state()}, target=first)
        self._commit_sweep(k, attempt + 1, raw, d)
        return count

    def _raw_rows(self, raw: RawSweep, d: Derived) -> tuple[float, float, list[Any], list[Any]]:
        """(started, ended, polls, stream) of a sweep's raw streams for the journal, in
        run time."""
        offset = self.context.time.offset
        polls = [
            (a + offset, b + offset, p)
            for a, b, p in zip(
                d.request.tolist(), d.reply.tolist(), d.positions.tolist(), strict=True
            )
        ]
        stream = [
            (
                r.started_s + offset, r.ended_s + offset, r.value,
                r.std if math.isfinite(r.std) else None, int(r.saturated),
                r.device_t_s, None if r.received_s is None else r.received_s + offset,
            )
            for r in raw.readings
        ]  # fmt: skip
        return raw.started_s + offset, raw.ended_s + offset, polls, stream

    def _commit_sweep(self, k: int, attempts: int, raw: RawSweep, d: Derived) -> None:
        """Journal the sweep (its merge ``d``), its raw streams, its samples and the
        targets it did not read (skipped), in one transaction."""
        c = self.context
        sweeps = c.plan.sweeps
        assert sweeps is not None
        merged, extra = d.samples, d.extra
        first, count = int(sweeps.first[k]), int(sweeps.count[k])
        state = c.sim_state()
        last = int(np.argmax(d.ended[merged.index])) if len(merged.index) else -1
        data = {
            "first": first, "count": count, "readings": len(raw.readings),
            "matched": len(d.matched.index), "kept": len(merged.index), "polls": len(raw.polls),
            "attempts": attempts,
        }  # fmt: skip
        started, ended, polls, stream = self._raw_rows(raw, d)
        read = set(merged.target.tolist())
        with c.journal.transaction():
            c.journal.sweep(k, "measured", started, ended, data, polls, stream)
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
                    c.skip(i, f"sweep {k}: no reading in the constant-velocity part")

    def _fly_sample(
        self, i: int, attempts: int, settled_s: float, angles: FloatArray,
        reading: StreamReading, smear: float, timing: float, extra: float,
        state: Mapping[str, Any],
    ) -> None:  # fmt: skip
        c = self.context
        std = reading.std if math.isfinite(reading.std) else 0.0
        offset = c.time.offset
        c.write_sample(
            i, attempts, angles.tolist(), settled_s + offset, state,
            exposure_s=reading.ended_s - reading.started_s, averages=1, n=1,
            counts=reading.value, counts_std=math.hypot(std, extra),
            saturated=int(reading.saturated), remeasured=0,
            started_s=reading.started_s + offset, ended_s=reading.ended_s + offset,
            smear_rad=smear, timing_rad=timing,
        )  # fmt: skip
