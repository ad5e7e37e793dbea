"""Axis configurations for tests that drive emulated Dynamixel buses."""

from __future__ import annotations

import math

from drivers.dynamixel.axis import AxisConfig


def axes(n: int = 3, **kw: object) -> list[AxisConfig]:
    """n axes on motors 1…n, each ±1 rad around the motor's middle (2048 ticks)."""
    base: dict[str, object] = {
        "min_rad": -1.0,
        "max_rad": 1.0,
        "zero_offset_rad": -math.pi,
        "profile_velocity_rad_s": 4.0,
        "profile_acceleration_rad_s2": 40.0,
    }
    base.update(kw)
    return [AxisConfig(name=f"axis{i}", motor_id=i, **base) for i in range(1, n + 1)]  # type: ignore[arg-type]
