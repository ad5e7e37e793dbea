"""Motor health against the pause conditions (`gonio.acquire.suspenders`, from the rig
file's ``health`` limits): what a check found."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from drivers.values import Health
from gonio.acquire.suspenders import Suspender


@dataclass(frozen=True)
class Assessment:
    """One health check: each axis's temperature (°C) and supply (V), what trips the
    suspenders (in words) and the hardware error flags any motor reports."""

    temperatures_c: dict[str, float]
    voltages_v: dict[str, float]
    problems: list[str]
    flags: dict[str, list[str]]

    def data(self, count: int) -> dict[str, Any]:
        """The journal's ``health`` event data (``count``: targets measured so far)."""
        return {
            "count": count,
            "temperatures_c": self.temperatures_c,
            "voltages_v": self.voltages_v,
            "problems": self.problems,
            "flags": self.flags,
        }


def assess(health: Mapping[str, Health], suspenders: Sequence[Suspender]) -> Assessment:
    """What ``health`` (per axis) says, against ``suspenders`` (their problems in order)."""
    return Assessment(
        temperatures_c={a: h.temperature_c for a, h in health.items()},
        voltages_v={a: h.voltage_v for a, h in health.items()},
        problems=[p for s in suspenders for p in s.problems(health)],
        flags={a: list(h.error_flags) for a, h in health.items() if h.error_flags},
    )
