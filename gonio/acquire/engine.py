"""The acquisition engine: one loop for every backend, written against the
`drivers.base` contract only (docs/explanations/acquisition.md).

For each target of the stored, ordered plan still to measure: check its pose against
the bus's limits (a pose outside them is skipped, never commanded) → move → wait until
settled → the rig's settle dwell → read the positions back → measure → if saturated,
measure again at half the exposure (plan option) → journal the raw sample. Between
targets, when due: a health check (pause while a suspender trips, e.g. a motor too hot or
its supply out of range: `gonio.acquire.suspenders`) and a calibration (the reference
standard, and a dark reading; when: `gonio.acquire.schedule.Calibrations`). The
reference is read at the start and at the end of every run. What the engine carries
from target to target, and rebuilds from the journal when a run resumes, is its
`gonio.acquire.state.RunState`. A fly plan is measured sweep after sweep instead, with
the same checks between sweeps (`gonio.acquire.fly.FlyLoop`, which the engine holds).

Faults follow the plan's ``acquisition.on_fault``: a `CommError` or `DetectorError`
is retried (in a calibration too), then the target skipped (journaled) or the run
aborted (a calibration's last attempt ends the run resumable); a `MotorFault` or
`MotionTimeout` stops every axis, is journaled with the motor's flags, and ends the run
resumable, unless the plan's ``on_fault.motor`` recovers the motor
(`gonio.acquire.recovery`: the target or calibration in flight is then done again).
A first Ctrl-C / SIGTERM finishes the sample in flight, a second stops at once
(`gonio.acquire.signals`); a stop request posted beside the run file does what the
first does, a pause request holds the axes between targets until a resume request
(`gonio.acquire.control`). Every outcome leaves the journal consistent and the run
resumable: `gonio acquire --resume` measures exactly the targets still missing.

Times: each journaled time is *run time* (`RunTime`): the simulated backend's virtual
clock (restored when a run resumes, so a resumed simulation is the uninterrupted one),
or on hardware the seconds since the run's first start by the wall clock.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drivers.base import dark_subtracted, reading_unit
from drivers.devices import Devices
from drivers.errors import (
    CommError,
    DetectorError,
    DriverError,
    LimitError,
    MotionTimeout,
    MotorFault,
)
from drivers.values import Reading
from gonio.acquire.control import ControlRequests, Request, StopRequested
from gonio.acquire.ending import EndSession, Outcome, Report, fault_data
from gonio.acquire.fly import FlyContext, FlyLoop
from gonio.acquire.health_check import HealthChecks
from gonio.acquire.measure import MOVE_TIMEOUT_S, TargetReading, measure_target, reading_fields
from gonio.acquire.observer import Observer, Unobserved
from gonio.acquire.recovery import MotorRecovery
from gonio.acquire.reference import Stage, calibration_data, read_standard
from gonio.acquire.runtime import RunTime, utc_now
from gonio.acquire.signals import RunInterrupted, StopRequests
from gonio.acquire.state import RunState, initial_state, latest_snapshot
from gonio.acquire.suspenders import Suspender, health_suspenders
from gonio.acquire.watch import ReadingWatch
from gonio.errors import GonioError
from gonio.planner import AcquisitionSpec, Plan
from gonio.rig import Rig
from gonio.store import Journal, JournalError, Run, commanded, coordinate, dumps, read_back

#: What ends a session early: each is journaled (`Engine._ending`), the session ended.
_ENDINGS = (RunInterrupted, DriverError, EndSession, GonioError)


@dataclass
class Engine:
    """Runs ``plan`` on ``devices`` into ``journal`` (see the module docstring).

    ``history``: the run as journaled so far (None for a new run). ``stage``: how the
    reference standard gets in view. ``calibrate_on_resume``: read the reference when a
    run resumes (hardware: conditions may have changed; a restored simulation: no).
    """

    plan: Plan
    devices: Devices
    journal: Journal
    stage: Stage
    time: RunTime
    history: Run | None = None
    calibrate_on_resume: bool = True
    retry_skipped: bool = False
    progress: Observer = field(default_factory=Unobserved)
    stops: StopRequests = field(default_factory=StopRequests)
    # Pause/resume/stop requests posted beside the run file (default: the journal's file's)
    control: ControlRequests | None = None
    move_timeout_s: float = MOVE_TIMEOUT_S
    # Set from the plan (and the history) when made:
    spec: AcquisitionSpec = field(init=False)
    rig: Rig = field(init=False)
    axes: tuple[str, ...] = field(init=False)
    suspenders: tuple[Suspender, ...] = field(init=False)  # consulted at each health check
    state: RunState = field(init=False)  # carried across targets and sessions
    _report: Report = field(init=False)  # this session's
    _busy_until: float = field(init=False, default=0.0)  # run time the step in flight ends
    _current: int | None = field(init=False, default=None)  # the target in flight
    _limits: dict[str, tuple[float, float]] | None = field(init=False, default=None)
    _watch: ReadingWatch = field(init=False)  # range changes and phase drift to journal
    _recovery: MotorRecovery = field(init=False)  # the plan's on_fault.motor
    _fly_loop: FlyLoop | None = field(init=False, default=None)  # a fly plan's loop
    _health: HealthChecks = field(init=False)  # the motors' health, pausing the run

    def __post_init__(self) -> None:
        self.spec = self.plan.spec.acquisition
        self.rig = self.plan.rig
        self.axes = self.rig.axes
        self.suspenders = health_suspenders(self.rig.spec.health)
        self.state = initial_state(self.spec, self.history)
        self._report = Report("completed", 0, 0)
        self.stops.remaining_s = lambda: self._busy_until - self.time.now()
        self._watch = ReadingWatch.of(self.devices.detector, self.time.offset, self.history)
        self._recovery = MotorRecovery.of(
            self.spec.on_fault.motor, self.devices, self.rig, self.spec.health.poll_s,
            self._event, self.history, self.stops.raise_if_requested,
        )  # fmt: skip
        self._health = HealthChecks(
            self.devices, self.spec.health, self.suspenders, self.time, self.state,
            self._recovery, self.stops, self._event, self._sim, self._hold_all,
        )  # fmt: skip
        if self.control is None:
            self.control = ControlRequests(self.journal.path)
        if self.plan.sweeps is not None:
            self._fly_loop = FlyLoop(self._fly_context())

    def _fly_context(self) -> FlyContext:
        """What the fly loop uses of the engine: its run's parts and its machinery."""

        def in_flight(target: int) -> None:
            self._current = target

        def busy_until(run_s: float) -> None:
            self._busy_until = run_s

        return FlyContext(
            plan=self.plan, devices=self.devices, journal=self.journal, time=self.time,
            progress=self.progress, stops=self.stops, spec=self.spec, rig=self.rig,
            axes=self.axes, move_timeout_s=self.move_timeout_s, recovery=self._recovery,
            between_targets=self._between_targets, obey=self._obey,
            within_limits=self._within_limits, skip=self._skip, hold_all=self._hold_all,
            event=self._event, sim_state=self._sim,
            write_sample=self._write_sample, in_flight=in_flight, busy_until=busy_until,
        )  # fmt: skip

    def todo(self) -> np.ndarray:
        """The plan indices this session measures, in the plan's order."""
        if self.history is None:
            return np.arange(len(self.plan))
        return self.history.missing(include_skipped=self.retry_skipped)

    # -- the run -------------------------------------------------------------------------
    def run(self) -> Report:
        """Open the devices, measure what is left, close them; the session's `Report`.
        A signal that ends the session early raises `RunInterrupted` after the pause
        was journaled and the devices closed."""
        todo = self.todo()
        report = self._report = Report("completed", 0, 0)
        interrupted: RunInterrupted | None = None
        # The session ends in the journal while the signal handlers are still ours: a
        # late second Ctrl-C must not skip it.
        with self.stops:
            with self.devices:
                try:
                    self._measure(todo)
                except _ENDINGS as exc:
                    report.outcome, report.message = self._ending(exc)
                    interrupted = exc if isinstance(exc, RunInterrupted) else None
                finally:
                    self.progress.close()
            self._end_session(report.outcome)
        if interrupted is not None:
            raise interrupted
        return report

    def _measure(self, todo: np.ndarray) -> None:
        """The loop: start, then each target (a health check and a calibration before
        it when due), then the closing calibration."""
        try:
            self._start(resuming=self.history is not None)
            measuring = False
            if self._fly_loop is not None:
                assert self.plan.sweeps is not None
                swept = self.plan.sweeps.swept  # a mixed plan's stop-and-go targets follow
                measuring = self._fly_loop.run(todo[todo < swept])
                todo = todo[todo >= swept]
                if not todo.size:
                    self._closing(measuring)
                    return
            if self.devices.simulation is not None:
                self.devices.simulation.expect(self.plan.angles[todo], todo)
            self.progress.start(self.plan, todo)
            for done, i in enumerate(todo.tolist()):
                self._between_targets()
                self._target(i)
                self.progress.advance(done + 1)
                self.stops.raise_if_requested()
                self._obey()
            self._closing(measuring or bool(todo.size))
        finally:
            self.stops.disarm()  # a signal now must not cut the ending short

    def _closing(self, measuring: bool) -> None:
        if self.state.calibrations.closing(self.state.count, measuring=measuring):
            self._calibrate("end")

    def _start(self, *, resuming: bool) -> None:
        restored = resuming and not self.calibrate_on_resume and self._restore_simulation()
        self._event("resume" if resuming else "start", {"targets_left": int(self.todo().size)})
        if self.devices.light is not None:  # a switchable lamp may be off at power-up
            self.devices.light.on()
        # A restored simulation keeps the uninterrupted run's schedule of health checks,
        # unless it stopped in a pause (then it goes on checking).
        if not restored or self.state.unhealthy:
            self._health.check()
        why = self.state.calibrations.opening(resuming=resuming, on_resume=self.calibrate_on_resume)
        if why is not None:
            self._calibrate(why)

    def _restore_simulation(self) -> bool:
        """Put the simulated backend in its state at the journal's end; whether it was."""
        simulation = self.devices.simulation
        state = None if self.history is None else latest_snapshot(self.history)
        if simulation is None or state is None:
            return False
        simulation.restore(state)
        return True

    def _obey(self) -> None:
        """Act on the control requests posted since the last target
        (`gonio.acquire.control`): a ``stop`` ends the session as a first Ctrl-C does; a
        ``pause`` holds the axes and waits (wall time) for a ``resume``."""
        assert self.control is not None
        requests = self.control.poll()
        paused: Request | None = None
        began = 0.0
        while True:
            for r in requests:
                if r.action == "stop":
                    raise StopRequested(r)
                if r.action == "pause" and paused is None:
                    self._hold_all()
                    self._event("pause", {"reason": "request", **r.data(), **self._sim()})
                    paused, began = r, time.monotonic()
                elif r.action == "resume" and paused is not None:
                    data = {"reason": "request", **r.data(), "paused_s": time.monotonic() - began}
                    self._event("resume", {**data, **self._sim()})
                    paused = None
            if paused is None:
                return
            self.stops.raise_if_requested()
            requests = self.control.wait(0.1)

    def _between_targets(self) -> None:
        if self.state.health_due.due(self.state.count, self.time.now()):
            self._health.check()
        if self.state.calibrations.due(self.state.count, self.time.now()):
            self._calibrate("scheduled")

    def _ending(self, exc: BaseException) -> tuple[Outcome, str]:
        """How the session ends on ``exc`` (one of `_ENDINGS`), journaled after every
        axis was told to hold."""
        self._hold_all()
        if isinstance(exc, RunInterrupted):
            # A step abandoned half-way is redone from the state last journaled (a
            # snapshot taken now would resume the simulation mid-step).
            state = {} if exc.abandoned else self._sim()
            data = {"reason": "signal", "signal": exc.args[0], "abandoned": exc.abandoned}
            kind = "pause"
            if isinstance(exc, StopRequested):  # its own kind: the run ends, resumable
                kind, data = "stop", {"reason": "request", **exc.request.data(), "abandoned": False}
            self._event(kind, {**data, **state})
            return "interrupted", f"stopped by {exc.args[0]}"
        if isinstance(exc, MotorFault | MotionTimeout):
            self._event("fault", {**fault_data(exc), **self._sim()}, target=self._current)
            return "fault", str(exc)
        if isinstance(exc, DriverError):  # outside a target's retries: a calibration, the light
            self._event("fault", {**fault_data(exc), **self._sim()})
            return "fault", str(exc)
        if isinstance(exc, EndSession):
            return exc.outcome, str(exc)
        return ("journal" if isinstance(exc, JournalError) else "aborted"), str(exc)

    def _end_session(self, outcome: Outcome) -> None:
        # A full disk: the session's end is all that is not recorded.
        with contextlib.suppress(JournalError):
            self.journal.end_session(utc_now(), outcome)

    def _hold_all(self) -> None:
        """Tell every axis to hold (the contract already did after a motion fault; again
        here so no path out of the loop leaves an axis moving)."""
        with contextlib.suppress(DriverError):
            self.devices.bus.stop()

    # -- journal helpers -----------------------------------------------------------------
    def _event(self, kind: str, data: Mapping[str, Any], target: int | None = None) -> None:
        self.journal.event(kind, self.time.now(), utc_now(), data, target)

    def _sim(self) -> dict[str, Any]:
        """``{"sim_state": …}`` on a simulated backend (at rest), else nothing."""
        simulation = self.devices.simulation
        state = None if simulation is None else simulation.snapshot()
        return {} if state is None else {"sim_state": state}

    # -- one target ----------------------------------------------------------------------
    def _within_limits(self, pose: np.ndarray) -> str | None:
        """Why ``pose`` must not be commanded (outside an axis's limits), or None."""
        if self._limits is None:  # configured once: the same for the whole run
            self._limits = self.devices.bus.limits()
        limits = self._limits
        for name, angle in zip(self.axes, pose.tolist(), strict=True):
            lo, hi = limits[name]
            if not (math.isfinite(angle) and lo <= angle <= hi):
                return f"axis {name!r}: {angle!r} rad is outside its limits [{lo:.6f}, {hi:.6f}]"
        return None

    def _target(self, i: int) -> None:
        self._current = i
        plan = self.plan
        pose = plan.angles[i]
        refused = self._within_limits(pose)
        if refused is not None:
            self._skip(i, refused)
            return
        exposure, averages = float(plan.exposure_s[i]), int(plan.averages[i])
        on_fault = self.spec.on_fault
        goal = dict(zip(self.axes, pose.tolist(), strict=True))
        for attempt in range(on_fault.retries + 1):
            self._busy_until = self.time.now() + float(plan.travel_s[i]) + exposure * averages
            try:
                measured = self._recovery.attempt(
                    lambda: measure_target(
                        self.devices, i, goal, exposure, averages,
                        settle_s=self.rig.spec.settle_s, timeout_s=self.move_timeout_s,
                    ),
                    target=i,
                )  # fmt: skip
                break
            except LimitError as exc:
                self._skip(i, str(exc))
                return
            except (CommError, DetectorError) as exc:
                last = attempt == on_fault.retries
                data = {**fault_data(exc), "attempt": attempt + 1, **self._sim()}
                if not last:
                    self._event("retry", data, target=i)
                    continue
                if on_fault.then == "skip":
                    self._skip(i, f"{type(exc).__name__} after {attempt + 1} attempts: {exc}")
                    return
                self._event("fault", data, target=i)
                raise EndSession("aborted", f"target {i}: {exc}") from None
        reading, exposure, remeasured = self._unsaturated(i, measured.reading, exposure, averages)
        self._journal_sample(i, attempt + 1, measured, reading, exposure, remeasured)
        for kind, data in self._watch.events(reading):
            self._event(kind, data, target=i)

    def _skip(self, i: int, reason: str) -> None:
        self._event("skip", {"reason": reason, **self._sim()}, target=i)
        self._report.skipped += 1

    def _unsaturated(
        self, i: int, reading: Reading, exposure: float, averages: int
    ) -> tuple[Reading, float, int]:
        """Measure again at half the exposure while saturated (plan option; not for a
        level reading, which a shorter exposure leaves the same: `reading_unit`)."""
        spec = self.spec.saturation
        shortest = self.devices.detector.exposure_range_s[0]
        level = reading_unit(self.devices.detector) != "counts"
        remeasured = 0
        while (
            reading.saturated
            and not level
            and spec.remeasure
            and remeasured < spec.attempts
            and exposure > shortest
        ):
            exposure = max(exposure / 2.0, shortest)
            reading = self.devices.detector.measure(exposure, averages)
            remeasured += 1
        return reading, exposure, remeasured

    def _journal_sample(
        self,
        i: int,
        attempts: int,
        measured: TargetReading,
        reading: Reading,
        exposure: float,
        remeasured: int,
    ) -> None:
        fields = reading_fields(reading, exposure, self.time.offset)
        self._write_sample(
            i, attempts, [measured.read_back[a] for a in self.axes],
            measured.settled_s + self.time.offset, self._sim(),
            exposure_s=fields["exposure_s"], averages=int(self.plan.averages[i]),
            n=reading.n, counts=reading.value, counts_std=fields["std"],
            saturated=int(reading.saturated), remeasured=remeasured,
            started_s=fields["started_s"], ended_s=fields["ended_s"],
            smear_rad=None, timing_rad=None,
        )  # fmt: skip

    def _write_sample(
        self,
        i: int,
        attempts: int,
        angles: list[float],
        settled_s: float,
        state: Mapping[str, Any],
        **measured: Any,
    ) -> None:
        """Journal target ``i``'s sample: the columns every sample has (the pose read back
        at ``angles`` and its pair, the plan's coordinates, the run time ``settled_s``),
        the ``measured`` ones (the reading, its window and uncertainty) and the
        simulation's ``state`` when it has one."""
        plan = self.plan
        wi, wo = self.rig.forward(np.array(angles, dtype=np.float64), self.rig.alignment)
        names = plan.coordinate_names
        row: dict[str, Any] = {  # the columns of `gonio.store.schema.samples_table`
            "target": i,
            "attempts": attempts,
            **{commanded(a): v for a, v in zip(self.axes, plan.angles[i].tolist(), strict=True)},
            **{read_back(a): v for a, v in zip(self.axes, angles, strict=True)},
            "wi_x": float(wi[0]), "wi_y": float(wi[1]), "wi_z": float(wi[2]),
            "wo_x": float(wo[0]), "wo_y": float(wo[1]), "wo_z": float(wo[2]),
            **{coordinate(c): v for c, v in zip(names, plan.coords[i].tolist(), strict=True)},
            **measured,
            "settled_s": settled_s,
            "utc": utc_now(),
            "temperatures_c": self.state.temperatures,
            "sim_state": dumps(state["sim_state"]) if state else None,
        }  # fmt: skip
        self.state.temperatures = None
        self.journal.sample(row)
        self.state.count += 1
        self._report.measured += 1

    # -- calibration ---------------------------------------------------------------------
    def _calibrate(self, why: str) -> None:
        """Read the reference standard (and a dark reading, unless the plan says not to
        or the detector's readings are dark-subtracted) and journal them as one
        ``calibration`` event."""
        spec, calibrations = self.spec.calibration, self.state.calibrations
        detector = self.devices.detector
        subtracted = dark_subtracted(detector)
        exposure = calibrations.exposure_s
        if exposure is None:
            shortest, longest = self.devices.detector.exposure_range_s
            exposure = float(np.clip(np.median(self.plan.exposure_s), shortest, longest))
        retries = self.spec.on_fault.retries
        for attempt in range(retries + 1):
            try:
                read = self._recovery.attempt(
                    lambda: read_standard(
                        self.devices, self.stage, self.rig, calibrations.k, exposure,
                        spec.averages, dark=spec.dark and not subtracted,
                        timeout_s=self.move_timeout_s,
                    )
                )  # fmt: skip
                break
            except (CommError, DetectorError) as exc:
                # A transient fault in a calibration is retried as in a target; after the
                # last attempt it ends the session resumable (a calibration is not skipped).
                if attempt == retries:
                    raise
                self._hold_all()
                failed = {**fault_data(exc), "attempt": attempt + 1, "calibration": why}
                self._event("retry", {**failed, **self._sim()})
        data = calibration_data(
            read, self.rig, why, calibrations.k, self.state.count, reading_unit(detector),
            self.time.offset,
        )  # fmt: skip
        data["reference"] |= self._watch.reference(read.reference.reading)
        data |= self._sim()
        if read.dark is None:
            data["dark_reason"] = "detector" if subtracted else "plan"
        self._event("calibration", data)
        for kind, event in self._watch.events(None):
            self._event(kind, event)
        calibrations.done(self.state.count, self.time.now(), read.exposure_s)
