"""How a rig axis maps onto a Dynamixel motor: configuration and unit conversion.

axis angle (rad) = zero_offset + direction · motor angle / gear_ratio, and motor angle =
ticks · 2π/4096. ``gear_ratio`` is motor revolutions per axis revolution; ``model`` and
``firmware``, when given, are what the motor must answer with
(`drivers.dynamixel.hygiene`). Profile velocity and acceleration are given for the
axis (rad/s, rad/s²) and converted to the motor's register units (0.229 rev/min,
214.577 rev/min²), rounded to the nearest step: the rates the motor runs are
`AxisConfig.profile_rates`, not the configured ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from drivers.dynamixel.control_table import (
    EXTENDED_POSITION_LIMIT,
    OPERATING_MODES,
    RAD_PER_TICK,
    RAD_S2_PER_ACCELERATION_UNIT,
    RAD_S_PER_VELOCITY_UNIT,
    TICKS_PER_REV,
    item,
)
from drivers.errors import LimitError

MODES = ("position", "extended_position")


@dataclass(frozen=True)
class AxisConfig:
    """One axis driven by one motor. Angles in radians, rates in rad/s and rad/s²."""

    name: str
    motor_id: int
    min_rad: float
    max_rad: float
    gear_ratio: float = 1.0
    zero_offset_rad: float = 0.0
    direction: int = 1
    mode: str = "position"
    profile_velocity_rad_s: float = 1.0
    profile_acceleration_rad_s2: float = 4.0
    #: The model number and firmware version the motor must answer with (None: any).
    model: int | None = None
    firmware: int | None = None

    def __post_init__(self) -> None:
        problems = []
        if not 0 <= self.motor_id <= 252:
            problems.append(f"motor_id {self.motor_id} is not in 0…252")
        if not (math.isfinite(self.min_rad) and math.isfinite(self.max_rad)):
            problems.append("limits must be finite")
        elif self.min_rad >= self.max_rad:
            problems.append(f"min_rad {self.min_rad} is not below max_rad {self.max_rad}")
        if not (math.isfinite(self.gear_ratio) and self.gear_ratio > 0):
            problems.append(f"gear_ratio {self.gear_ratio} must be positive")
        if self.direction not in (1, -1):
            problems.append(f"direction {self.direction} must be +1 or -1")
        if self.mode not in MODES:
            problems.append(f"mode {self.mode!r} must be one of {', '.join(MODES)}")
        if not self.profile_velocity_rad_s > 0 or not self.profile_acceleration_rad_s2 > 0:
            problems.append("profile velocity and acceleration must be positive")
        if self.model is not None and not 0 <= self.model <= 0xFFFF:
            problems.append(f"model {self.model} is not a model number (0…65535)")
        if self.firmware is not None and not 0 <= self.firmware <= 0xFF:
            problems.append(f"firmware {self.firmware} is not a firmware version (0…255)")
        if problems:
            raise ValueError(f"axis {self.name!r}: " + "; ".join(problems))
        lo, hi = sorted((self.to_ticks_exact(self.min_rad), self.to_ticks_exact(self.max_rad)))
        span = (
            (0, TICKS_PER_REV - 1)
            if self.mode == "position"
            else (
                -EXTENDED_POSITION_LIMIT,
                EXTENDED_POSITION_LIMIT,
            )
        )
        if lo < span[0] - 0.5 or hi > span[1] + 0.5:
            raise ValueError(
                f"axis {self.name!r}: limits [{self.min_rad}, {self.max_rad}] rad need motor "
                f"ticks {lo:.0f}…{hi:.0f}, outside {span[0]}…{span[1]} in {self.mode} mode "
                "(adjust zero_offset_rad or use extended_position)"
            )

    @property
    def operating_mode(self) -> int:
        return OPERATING_MODES[self.mode]

    def to_ticks_exact(self, angle_rad: float) -> float:
        return self.direction * (angle_rad - self.zero_offset_rad) * self.gear_ratio / RAD_PER_TICK

    def to_ticks(self, angle_rad: float) -> int:
        """The goal position register value for an axis angle (nearest tick)."""
        return round(self.to_ticks_exact(angle_rad))

    def to_rad(self, ticks: int) -> float:
        """The axis angle of a present position register value."""
        return self.zero_offset_rad + self.direction * ticks * RAD_PER_TICK / self.gear_ratio

    @property
    def resolution_rad(self) -> float:
        """One motor tick, in axis radians."""
        return RAD_PER_TICK / self.gear_ratio

    def tick_limits(self) -> tuple[int, int]:
        """(min, max) motor ticks of the axis limits, for the motor's own position limits."""
        a, b = self.to_ticks_exact(self.min_rad), self.to_ticks_exact(self.max_rad)
        return math.ceil(min(a, b) - 1e-9), math.floor(max(a, b) + 1e-9)

    def profile_registers(self) -> tuple[int, int]:
        """(Profile Velocity, Profile Acceleration) register values, at least 1 each."""
        velocity = self.profile_velocity_rad_s * self.gear_ratio / RAD_S_PER_VELOCITY_UNIT
        acceleration = (
            self.profile_acceleration_rad_s2 * self.gear_ratio / RAD_S2_PER_ACCELERATION_UNIT
        )
        high_v = item("profile_velocity").high or 32767
        high_a = item("profile_acceleration").high or 32767
        return (
            min(high_v, max(1, round(velocity))),
            min(high_a, max(1, round(acceleration))),
        )

    def profile_rates(self) -> tuple[float, float]:
        """(velocity rad/s, acceleration rad/s²) of the axis under its `profile_registers`:
        what the motor runs, each rate rounded to the nearest register step (90 °/s² on a
        direct axis is 4 × 214.577 rev/min², 85.8 °/s²)."""
        velocity, acceleration = self.profile_registers()
        return (
            velocity * RAD_S_PER_VELOCITY_UNIT / self.gear_ratio,
            acceleration * RAD_S2_PER_ACCELERATION_UNIT / self.gear_ratio,
        )

    def rate_registers(self, velocity: float, acceleration: float) -> tuple[int, int]:
        """(Profile Velocity, Profile Acceleration) register values of a sweep's rates
        (rad/s, rad/s²; checked against the configured ones already); `LimitError` for a
        rate below one register step (0 would mean "unlimited")."""
        v = round(velocity * self.gear_ratio / RAD_S_PER_VELOCITY_UNIT)
        a = round(acceleration * self.gear_ratio / RAD_S2_PER_ACCELERATION_UNIT)
        if v < 1 or a < 1:
            raise LimitError(
                f"axis {self.name!r}: sweep velocity {velocity:.6g} rad/s or acceleration "
                f"{acceleration:.6g} rad/s² is below one register step of the motor "
                f"({RAD_S_PER_VELOCITY_UNIT / self.gear_ratio:.6g} rad/s, "
                f"{RAD_S2_PER_ACCELERATION_UNIT / self.gear_ratio:.6g} rad/s²); "
                "nothing was sent"
            )
        return v, a

    def contains(self, angle_rad: float) -> bool:
        return math.isfinite(angle_rad) and self.min_rad <= angle_rad <= self.max_rad

    def clamp_ticks(self, ticks: int) -> int:
        """``ticks`` clamped to the axis's limits in motor ticks (in position mode also the
        motor's own Min/Max Position Limit, beyond which it would refuse the goal)."""
        low, high = self.tick_limits()
        return min(max(ticks, low), high)

    def goal_ticks(self, angle_rad: float) -> int:
        """The goal register of ``angle_rad`` (`clamp_ticks`); `LimitError` outside the
        axis's limits or not finite (nothing is sent)."""
        if not self.contains(float(angle_rad)):
            raise LimitError(
                f"axis {self.name!r}: target {angle_rad!r} rad ({math.degrees(angle_rad):.3f}°) "
                f"is outside its limits [{self.min_rad:.6f}, {self.max_rad:.6f}] rad; "
                "nothing was sent"
            )
        return self.clamp_ticks(self.to_ticks(float(angle_rad)))
