"""The engine's health checks (`HealthChecks`): read every motor's health, journal it,
and while a suspender trips hold the axes and read again every ``poll_s`` until none
does, or the pause outlasts the plan's ``pause_timeout_minutes`` (`Suspension`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from drivers.devices import Devices
from gonio.acquire.ending import EndSession
from gonio.acquire.health import assess
from gonio.acquire.recovery import MotorRecovery
from gonio.acquire.runtime import RunTime
from gonio.acquire.signals import StopRequests
from gonio.acquire.state import RunState
from gonio.acquire.suspenders import Step, Suspender, Suspension
from gonio.planner import HealthSpec
from gonio.store import dumps


@dataclass(frozen=True)
class HealthChecks:
    """Health checks on ``devices`` under ``spec`` and the rig's ``suspenders``, into the
    run's ``state``; ``event`` journals, ``sim_state`` is what a simulation adds to an
    event, ``hold_all`` holds every axis."""

    devices: Devices
    spec: HealthSpec
    suspenders: tuple[Suspender, ...]
    time: RunTime
    state: RunState
    recovery: MotorRecovery
    stops: StopRequests
    event: Callable[[str, Mapping[str, Any]], None]
    sim_state: Callable[[], dict[str, Any]]
    hold_all: Callable[[], None]

    def check(self) -> None:
        """Read every motor's health; while a suspender trips, hold the axes and read
        again every ``poll_s`` until none does (`Suspension`)."""
        suspension = Suspension(self.time.now(), self.spec.pause_timeout_minutes)
        while True:
            step = suspension.consult(self.read())
            if step is Step.GO:
                return
            if step is Step.RESUME:
                paused_s = suspension.paused_s(self.time.now())
                self.event("resume", {"reason": "health", "paused_s": paused_s, **self.sim_state()})
                return
            if step is Step.PAUSE:
                self.hold_all()
                problems = suspension.problems
                self.event("pause", {"reason": "health", "problems": problems, **self.sim_state()})
            if suspension.expired(self.time.now()):
                raise EndSession("paused", suspension.reason())
            self.stops.raise_if_requested()
            self.devices.clock.sleep(self.spec.poll_s)

    def read(self) -> list[str]:
        """Read every motor's health and journal it; what trips the suspenders (`EndSession`
        if a motor reports a hardware error)."""
        found = assess(self.devices.bus.health(), self.suspenders)
        self.event("health", {**found.data(self.state.count), **self.sim_state()})
        self.state.health_due.done(self.state.count, self.time.now())
        self.state.temperatures = dumps(found.temperatures_c)
        if found.flags and not self.recovery.flagged(found.flags):
            axis, flags = next(iter(found.flags.items()))
            raise EndSession("fault", f"axis {axis!r} reports a hardware error: {', '.join(flags)}")
        return found.problems
