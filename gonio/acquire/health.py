"""Motor health against the rig file's ``health`` limits: what a check found."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from drivers.base import Health
from gonio.rig.schema import HealthLimitsSpec


@dataclass(frozen=True)
class Assessment:
    """One health check: each axis's temperature (°C) and supply (V), the limits they
    break (in words) and the hardware error flags any motor reports."""

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


def assess(health: Mapping[str, Health], limits: HealthLimitsSpec) -> Assessment:
    """What ``health`` (per axis) says against ``limits``."""
    hot = [
        f"{a} at {h.temperature_c:g} °C (limit {limits.max_temperature_c:g})"
        for a, h in health.items()
        if h.temperature_c > limits.max_temperature_c
    ]
    supply = [
        f"{a} supply {h.voltage_v:g} V (limits {limits.min_voltage_v:g}–{limits.max_voltage_v:g})"
        for a, h in health.items()
        if not limits.min_voltage_v <= h.voltage_v <= limits.max_voltage_v
    ]
    return Assessment(
        temperatures_c={a: h.temperature_c for a, h in health.items()},
        voltages_v={a: h.voltage_v for a, h in health.items()},
        problems=hot + supply,
        flags={a: list(h.error_flags) for a, h in health.items() if h.error_flags},
    )
