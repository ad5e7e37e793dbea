"""Motors that recover by policy (the plan's ``acquisition.on_fault.motor``), never limp
silently.

A motor that reports a hardware error (its Hardware Error Status: overload,
overheating, input voltage, encoder) raises `drivers.errors.MotorFault`, and the bus has
already told every axis to hold. With ``action: stop`` (the default) the run ends
resumable. With ``action: recover`` `MotorRecovery.attempt` runs the step again after
a recovery, each stage journaled as a ``recovery`` event (``step``):

``diagnosed``
    every axis held again; the motor's error flags, temperature, input voltage and load
    as it reports them now, and which recovery of this motor in this run it is;
``cooling`` / ``cooled``
    when the cause is heat (the overheating flag, or a temperature at or above the
    rig's ``health.max_temperature_c``): the wait, on the run's clock, until the motor
    reads below that limit, polled every ``health.poll_s`` of the plan, at most
    ``cool_down_minutes`` (a first Ctrl-C ends it: the session pauses, the step in
    flight abandoned, and a resume measures it);
``rebooted``
    the motor rebooted back into the configuration the bus gave it when it opened
    (`drivers.base.MotorBus.recover`): where it held before and where it reads after,
    their difference and the rig's ``health.position_tolerance_deg``;
``recovered``
    the position agrees: the step in flight (a target, a fly plan's sweep, or a
    calibration) runs again; a motor a health check found reporting an error between
    targets is recovered the same way, and the run goes on;
``failed``
    a recovery that cannot go on (the motor did not cool in time, its error came back
    after the reboot, it did not answer, its position disagrees, or it was already
    rebooted ``max_recoveries`` times in this run): the run stops resumable with a
    ``fault`` event, as with ``stop``.

Recoveries are counted per motor per run: a resumed session counts the ``rebooted``
events its journal already holds.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

from drivers.devices import Devices
from drivers.errors import DriverError, MotorFault
from drivers.values import Health
from gonio.acquire.signals import RunInterrupted
from gonio.planner import MotorFaultSpec
from gonio.rig import Rig
from gonio.store import Run

T = TypeVar("T")

#: Journals one event: kind, data, target (the engine's ``_event``).
Journaling = Callable[[str, Mapping[str, Any], int | None], None]

#: The journal's event kind of every recovery step.
# A flag a reboot must not clear unattended: the e-manual reads it as a fault in the
# motor's circuit or its supply, which a person has to look at.
NEVER_RECOVERED = frozenset({"electrical_shock"})

KIND = "recovery"


class NotRecovered(Exception):
    """A recovery that cannot go on, in words (journaled as ``failed``)."""


@dataclass
class MotorRecovery:
    """The plan's motor-fault policy ``spec`` on ``devices``, with the rig's limits
    (``rig``: ``health.max_temperature_c``, ``health.position_tolerance_deg``), polling
    a hot motor every ``poll_s`` (s); ``event`` journals, ``check`` raises when a stop
    was requested (called while waiting). ``done`` counts the reboots of each axis in
    this run so far."""

    spec: MotorFaultSpec
    devices: Devices
    rig: Rig
    poll_s: float
    event: Journaling
    check: Callable[[], None] = lambda: None
    done: Counter[str] = field(default_factory=Counter)

    @classmethod
    def of(
        cls,
        spec: MotorFaultSpec,
        devices: Devices,
        rig: Rig,
        poll_s: float,
        event: Journaling,
        history: Run | None = None,
        check: Callable[[], None] = lambda: None,
    ) -> MotorRecovery:
        """The policy for a session: the reboots already in ``history`` count."""
        return cls(spec, devices, rig, poll_s, event, check, rebooted(history))

    def attempt(self, step: Callable[[], T], target: int | None = None) -> T:
        """``step()``; after a `MotorFault` it recovers the motor (``action: recover``)
        and runs ``step`` again, as often as the policy allows. With ``stop`` the fault
        propagates as it came; one it cannot recover as a new `MotorFault` saying why
        (from the first)."""
        while True:
            try:
                return step()
            except MotorFault as exc:
                if self.spec.action != "recover" or exc.axis is None:
                    raise
                self.recover(exc, target)

    def flagged(self, flags: Mapping[str, Sequence[str]]) -> bool:
        """Recover each axis a health check found reporting a hardware error (``flags``
        per axis) and say so (True); False, doing nothing, when the policy is stop."""
        if self.spec.action != "recover":
            return False
        motor_ids = {a.name: a.motor_id for a in self.rig.bus_axes()}
        for axis, found in flags.items():
            fault = MotorFault(
                f"motor {motor_ids[axis]} (axis {axis!r}) reports a hardware error: "
                f"{', '.join(found)}",
                motor_id=motor_ids[axis],
                axis=axis,
                flags=tuple(found),
            )
            self.recover(fault)
        return True

    def recover(self, fault: MotorFault, target: int | None = None) -> None:
        """Recover the motor of ``fault`` (journaled step by step); a `MotorFault`
        naming why when it cannot."""
        axis = fault.axis
        assert axis is not None
        n = self.done[axis] + 1
        base = {"axis": axis, "motor_id": fault.motor_id, "recovery": n}
        try:
            self._recover(fault, axis, n, base, target)
        except (DriverError, NotRecovered) as exc:
            reason = str(exc) if isinstance(exc, NotRecovered) else f"{type(exc).__name__}: {exc}"
            self.event(KIND, {**base, "step": "failed", "reason": reason}, target)
            raise MotorFault(
                f"motor {fault.motor_id} (axis {axis!r}) reported {', '.join(fault.flags)} "
                f"and was not recovered: {reason}",
                motor_id=fault.motor_id,
                axis=axis,
                flags=fault.flags,
            ) from exc

    def _recover(
        self, fault: MotorFault, axis: str, n: int, base: dict[str, Any], target: int | None
    ) -> None:
        bus = self.devices.bus
        bus.stop()  # every axis holds (the contract already told them; again, to be sure)
        health = bus.health()[axis]
        self.event(
            KIND,
            {
                **base,
                "step": "diagnosed",
                "error": str(fault),
                "flags": list(health.error_flags or fault.flags),
                **_condition(health),
                "max_recoveries": self.spec.max_recoveries,
            },
            target,
        )
        if NEVER_RECOVERED & {*health.error_flags, *fault.flags}:
            raise NotRecovered(
                "an electrical shock is never recovered unattended: check the motor's "
                "wiring and supply, then reboot it by hand (gonio motors reboot)"
            )
        if n > self.spec.max_recoveries:
            raise NotRecovered(
                f"rebooted {self.spec.max_recoveries} times in this run already "
                "(the plan's on_fault.motor.max_recoveries)"
            )
        limit = self.rig.spec.health.max_temperature_c
        if "overheating" in (*health.error_flags, *fault.flags) or health.temperature_c >= limit:
            self._cool(axis, health, limit, base, target)
        recovered = bus.recover(axis)
        self.done[axis] += 1
        deviation = math.degrees(abs(recovered.position_rad - recovered.held_rad))
        tolerance = self.rig.spec.health.position_tolerance_deg
        self.event(
            KIND,
            {
                **base,
                "step": "rebooted",
                "held_rad": recovered.held_rad,
                "position_rad": recovered.position_rad,
                "deviation_deg": deviation,
                "tolerance_deg": tolerance,
            },
            target,
        )
        if not deviation <= tolerance:
            raise NotRecovered(
                f"after the reboot it reads {deviation:.4g}° from where it held "
                f"(tolerance {tolerance:g}°, the rig's health.position_tolerance_deg); "
                "re-home it"
            )
        self.event(KIND, {**base, "step": "recovered"}, target)

    def _cool(
        self, axis: str, health: Health, limit: float, base: dict[str, Any], target: int | None
    ) -> None:
        """Wait on the run's clock until ``axis`` reads below ``limit`` (°C)."""
        clock = self.devices.clock
        longest = 60.0 * self.spec.cool_down_minutes
        self.event(
            KIND,
            {
                **base,
                "step": "cooling",
                "temperature_c": health.temperature_c,
                "below_c": limit,
                "max_wait_s": longest,
            },
            target,
        )
        began = clock.now()
        temperature = health.temperature_c
        while temperature >= limit:
            if clock.now() - began >= longest:
                raise NotRecovered(
                    f"still {temperature:g} °C after {self.spec.cool_down_minutes:g} min "
                    f"(it must cool below the rig's health.max_temperature_c, {limit:g} °C)"
                )
            try:
                self.check()
            except RunInterrupted as exc:  # mid-step: the target in flight is redone
                raise RunInterrupted(exc.signum, abandoned=True) from None
            clock.sleep(self.poll_s)
            temperature = self.devices.bus.health()[axis].temperature_c
        waited = clock.now() - began
        self.event(
            KIND,
            {**base, "step": "cooled", "temperature_c": temperature, "waited_s": waited},
            target,
        )


def _condition(health: Health) -> dict[str, Any]:
    return {
        "temperature_c": health.temperature_c,
        "voltage_v": health.voltage_v,
        "load_pct": health.load_pct,
    }


def rebooted(run: Run | None) -> Counter[str]:
    """The reboots of each axis a run's journal holds (none for a new run)."""
    if run is None:
        return Counter()
    return Counter(
        str(e.data["axis"]) for e in run.of_kind(KIND) if e.data.get("step") == "rebooted"
    )


def summaries(run: Run) -> list[dict[str, Any]]:
    """One dict per recovery in the run's journal, in order: ``axis``, ``motor_id``,
    ``recovery`` (its number for that motor), ``target``, ``t_s``, ``flags``,
    ``temperature_c``, ``load_pct``, ``waited_s`` (cooling; None when not hot),
    ``deviation_deg`` (None when not rebooted), ``outcome`` (``recovered``, ``failed``
    or None: the session ended in between) and ``reason`` (a failure's)."""
    out: list[dict[str, Any]] = []
    for e in run.of_kind(KIND):
        data = e.data
        step = data.get("step")
        if step == "diagnosed" or not out:
            out.append(
                {
                    "axis": data.get("axis"),
                    "motor_id": data.get("motor_id"),
                    "recovery": data.get("recovery"),
                    "target": e.target,
                    "t_s": e.t_s,
                    "flags": list(data.get("flags", ())),
                    "temperature_c": data.get("temperature_c"),
                    "load_pct": data.get("load_pct"),
                    "waited_s": None,
                    "deviation_deg": None,
                    "outcome": None,
                    "reason": None,
                }
            )
        last = out[-1]
        if step == "cooled":
            last["waited_s"] = data.get("waited_s")
        elif step == "rebooted":
            last["deviation_deg"] = data.get("deviation_deg")
        elif step in ("recovered", "failed"):
            last["outcome"] = step
            last["reason"] = data.get("reason")
    return out


def describe(run: Run) -> list[str]:
    """A line per recovery in the run's journal (what `gonio info` prints)."""
    lines = []
    for r in summaries(run):
        where = "a calibration" if r["target"] is None else f"target {r['target']}"
        said = ", ".join(r["flags"]) or "a hardware error"
        condition = [] if r["temperature_c"] is None else [f"{r['temperature_c']:g} °C"]
        if r["load_pct"] is not None:
            condition.append(f"load {r['load_pct']:.0f} %")
        parts = [f"{said} ({', '.join(condition)})" if condition else said]
        if r["waited_s"] is not None:
            parts.append(f"cooled {r['waited_s']:.0f} s")
        if r["deviation_deg"] is not None:
            parts.append(f"rebooted, {r['deviation_deg']:.3g}° from its hold")
        if r["outcome"] == "recovered":
            parts.append("measured again")
        elif r["outcome"] == "failed":
            parts.append(f"not recovered: {r['reason']}")
        else:
            parts.append("the session ended during it")
        lines.append(
            f"    recovery {r['recovery']} of {r['axis']} (motor {r['motor_id']}) at {where}: "
            + "; ".join(parts)
        )
    if lines:
        lines.insert(0, f"  {'motor recoveries':<24}{len(lines):>10}")
    return lines
