"""Pause conditions the engine consults between targets, in the manner of bluesky's
suspenders: small objects that look at what the instrument reports and say what holds
the run, in words.

A `Suspender` looks at every motor's health (`drivers.values.Health`, per axis); the
rig's are `health_suspenders` (the rig file's ``health`` limits: a temperature ceiling
and a supply band). At a health check the engine reads the health once and asks each
suspender; a `Suspension` is that check's state: running, paused (a suspender tripped:
the axes hold and the health is read again every ``poll_s``), then resumed once none
trips, or given up after the plan's ``pause_timeout_minutes`` (the session ends
resumable).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import Protocol

from drivers.values import Health
from gonio.rig import HealthLimitsSpec


class Suspender(Protocol):
    """A condition that holds the run between targets."""

    def problems(self, health: Mapping[str, Health]) -> list[str]:
        """What trips it in ``health`` (per axis), one line per axis; empty: nothing."""
        ...


@dataclass(frozen=True)
class TemperatureCeiling:
    """Trips while a motor's internal temperature is above ``max_c`` (°C)."""

    max_c: float

    def problems(self, health: Mapping[str, Health]) -> list[str]:
        return [
            f"{a} at {h.temperature_c:g} °C (limit {self.max_c:g})"
            for a, h in health.items()
            if h.temperature_c > self.max_c
        ]


@dataclass(frozen=True)
class SupplyBand:
    """Trips while a motor's supply voltage is outside [``min_v``, ``max_v``] (V)."""

    min_v: float
    max_v: float

    def problems(self, health: Mapping[str, Health]) -> list[str]:
        return [
            f"{a} supply {h.voltage_v:g} V (limits {self.min_v:g}–{self.max_v:g})"
            for a, h in health.items()
            if not self.min_v <= h.voltage_v <= self.max_v
        ]


def health_suspenders(limits: HealthLimitsSpec) -> tuple[Suspender, ...]:
    """The suspenders of a rig file's ``health`` limits, in the order their problems are
    reported (temperatures, then supplies)."""
    return (
        TemperatureCeiling(limits.max_temperature_c),
        SupplyBand(limits.min_voltage_v, limits.max_voltage_v),
    )


class Step(Enum):
    """What the engine does after a health reading (`Suspension.consult`)."""

    GO = "go"  # nothing tripped: the run goes on
    PAUSE = "pause"  # a suspender tripped: hold the axes, journal the pause, wait
    WAIT = "wait"  # still tripped: wait, then read again
    RESUME = "resume"  # cleared after a pause: journal the resume, the run goes on


@dataclass
class Suspension:
    """One health check's state, from ``started_s`` (run time, s, before its first
    reading): ``paused`` once a suspender tripped; ``problems`` the last reading's.
    Still tripped ``timeout_minutes`` after the start, it is `expired`."""

    started_s: float
    timeout_minutes: float
    paused: bool = False
    problems: list[str] = field(default_factory=list)

    def consult(self, problems: list[str]) -> Step:
        """The step after a reading whose suspenders found ``problems``."""
        self.problems = problems
        if not problems:
            return Step.RESUME if self.paused else Step.GO
        if self.paused:
            return Step.WAIT
        self.paused = True
        return Step.PAUSE

    def paused_s(self, now_s: float) -> float:
        """Seconds since the check began, at run time ``now_s``."""
        return now_s - self.started_s

    def expired(self, now_s: float) -> bool:
        """Whether the pause lasted its timeout at run time ``now_s``."""
        return now_s - self.started_s >= 60.0 * self.timeout_minutes

    def reason(self) -> str:
        """Why the session ends when the pause `expired`."""
        return f"paused {self.timeout_minutes:g} min for {self.problems[0]}; it did not clear"
