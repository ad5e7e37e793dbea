"""Streaming a trajectory's set-points to X-series motors (`DynamixelBus.follow`).

Per period one SYNC_WRITE of Profile Acceleration, Profile Velocity and Goal Position
(addresses 108-119, contiguous) for every axis of the trajectory, then one poll. The
motors run velocity-based profiles, and a new goal re-plans the profile from the
present position and velocity, so the registers of set-point k are chosen for the
motor to run along the path without braking (`setpoint_registers`):

* the goal is a look-ahead set-point, `lookahead` periods on, but never past a turning
  point of its axis or the last set-point (every goal is a set-point: inside the limits);
* the profile velocity is the path's speed at set-point k + 1 (the mean of the straight
  segments around it, the slope of the smooth time law the set-points sample), its
  rounding to the register step carried from one set-point to the next so that the
  distance commanded does not drift, at least one step (0 means "unlimited");
* the profile acceleration is that speed's change over one period, but at least what
  keeps the braking distance short of the look-ahead goal (the motor cruises), rounded
  up to the register step and at most the configured one.

Tracking: a motor that can change its speed by the path's change within one period
stays within about a · period² / 8 of the straight segments (the smooth curve's
distance from its chords); the contract suite states each backend's bound.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from drivers.base import Clock
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import (
    RAD_PER_TICK,
    RAD_S2_PER_ACCELERATION_UNIT,
    RAD_S_PER_VELOCITY_UNIT,
)
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import DriverError
from drivers.trajectory import Followed, Trajectory, check_trajectory, tracking_error
from drivers.values import StampedPositions

#: The items one set-point writes, in address order.
SETPOINT_ITEMS = ("profile_acceleration", "profile_velocity", "goal_position")
#: The look-ahead keeps each axis's braking distance at its fastest within this share of
#: the distance to its goal at its configured acceleration (`lookahead`).
BRAKING_SHARE = 0.125


def lookahead(trajectory: Trajectory, top_acceleration: NDArray[np.float64]) -> NDArray[np.int64]:
    """(A,) periods each axis's goal runs ahead of the path: enough that braking from its
    fastest speed v at `BRAKING_SHARE` of its configured acceleration a fits in the
    distance covered meanwhile (v · (L − 1) · period ≥ v² / (2 · share · a))."""
    fastest = np.max(np.abs(trajectory.velocities()), axis=0)
    periods = fastest / (2.0 * BRAKING_SHARE * top_acceleration * trajectory.period_s)
    return np.asarray(1 + np.ceil(periods), dtype=np.int64)


def _turns(trajectory: Trajectory) -> NDArray[np.int64]:
    """(K, A) for each set-point, the next set-point at which its axis turns back (the
    last set-point if it never does)."""
    k_last = len(trajectory) - 1
    step = np.sign(np.diff(trajectory.goals, axis=0))  # (K − 1, A)
    m = np.arange(len(step))[:, None]
    last = np.maximum.accumulate(np.where(step != 0, m, -1), axis=0)
    direction = np.where(last >= 0, np.take_along_axis(step, np.maximum(last, 0), axis=0), 0.0)
    change = np.zeros(step.shape, dtype=bool)
    change[1:] = direction[1:] != direction[:-1]
    at = np.where(change, m, k_last)  # a turn (or the first motion) at set-point m
    turns = np.full((len(trajectory), step.shape[1]), k_last, dtype=np.int64)
    # the first turn strictly after set-point k: the minimum of ``at`` over m > k
    turns[: len(step) - 1] = np.minimum.accumulate(at[::-1], axis=0)[::-1][1:]
    return turns


def setpoint_registers(trajectory: Trajectory, axes: Sequence[AxisConfig]) -> NDArray[np.int64]:
    """(K, A, 3) the Profile Acceleration, Profile Velocity and Goal Position registers of
    each set-point for the trajectory's axes ``axes`` (the module docstring). The
    trajectory is checked already (`drivers.trajectory.check_trajectory`)."""
    period = trajectory.period_s
    goals = trajectory.goals
    k_count = len(goals)
    gear = np.array([a.gear_ratio for a in axes])
    configured = np.array([a.profile_registers() for a in axes])  # (A, 2) velocity, acceleration
    top_a = np.array([a.profile_acceleration_rad_s2 for a in axes])
    # the path's speed at each set-point (rest at both ends), aimed at one period ahead
    v = trajectory.velocities()
    smooth = np.zeros_like(goals)
    smooth[1:-1] = 0.5 * (v[:-1] + v[1:])
    aim = np.zeros_like(goals)
    aim[:-1] = smooth[1:]
    change = np.abs(np.diff(np.vstack([np.zeros((1, len(axes))), aim]), axis=0)) / period
    # goals: a look-ahead set-point, not past the axis's next turn
    k = np.arange(k_count)[:, None]
    ahead = np.minimum(
        np.minimum(k + lookahead(trajectory, top_a)[None, :], _turns(trajectory)), k_count - 1
    )
    target = np.take_along_axis(goals, ahead, axis=0)
    distance = np.abs(target - goals)
    room = np.maximum(distance - np.abs(aim) * period, 0.5 * distance)
    braking = np.where(room > 0, aim * aim / (2.0 * np.where(room > 0, room, 1.0)), 0.0)
    accel = np.maximum(change, braking) * gear / RAD_S2_PER_ACCELERATION_UNIT
    accel_reg = np.clip(np.ceil(accel - 1e-9), 1, configured[:, 1])
    # speed in register steps, its rounding carried on (the distance commanded stays exact)
    steps = np.cumsum(np.abs(aim) * gear / RAD_S_PER_VELOCITY_UNIT, axis=0)
    rounded = np.round(steps)
    speed_reg = np.clip(
        np.diff(np.vstack([np.zeros((1, len(axes))), rounded]), axis=0), 1, configured[:, 0]
    )
    direction = np.array([a.direction for a in axes])
    zero = np.array([a.zero_offset_rad for a in axes])
    ticks = np.round(direction * (target - zero) * gear / RAD_PER_TICK)
    limits = np.array([a.tick_limits() for a in axes])
    ticks = np.clip(ticks, limits[:, 0], limits[:, 1])
    return np.stack([accel_reg, speed_reg, ticks], axis=-1).astype(np.int64)


@dataclass(frozen=True, eq=False)
class SetpointPlan:
    """A checked trajectory and its set-points' registers (K, A, 3) for ``axes``."""

    trajectory: Trajectory
    axes: tuple[AxisConfig, ...]
    registers: NDArray[np.int64]

    @classmethod
    def of(cls, trajectory: Trajectory, axes: Mapping[str, AxisConfig]) -> SetpointPlan:
        """Check ``trajectory`` against the configured limits and rates of ``axes`` (all
        the bus's: `DriverError` for an unknown one, `LimitError`) and plan its registers."""
        check_trajectory(
            trajectory,
            {n: (a.min_rad, a.max_rad) for n, a in axes.items()},
            {n: a.profile_velocity_rad_s for n, a in axes.items()},
            {n: a.profile_acceleration_rad_s2 for n, a in axes.items()},
        )
        named = tuple(axes[n] for n in trajectory.axes)
        return cls(trajectory, named, setpoint_registers(trajectory, named))

    @property
    def motor_ids(self) -> list[int]:
        return [a.motor_id for a in self.axes]

    def last_goals(self) -> dict[str, int]:
        """{axis: Goal Position} of the last set-point."""
        return {a.name: int(t) for a, t in zip(self.axes, self.registers[-1, :, 2], strict=True)}

    def check_start(self, state: Mapping[str, tuple[bool, int]], tolerance: int) -> None:
        """`DriverError` unless every axis of ``state`` ({axis: (moving, present ticks)})
        is at rest, the trajectory's within ``tolerance`` ticks of set-point 0."""
        start = {
            a.name: min(max(a.to_ticks(float(x)), a.tick_limits()[0]), a.tick_limits()[1])
            for a, x in zip(self.axes, self.trajectory.goals[0], strict=True)
        }
        off = [
            name
            for name, (moving, ticks) in state.items()
            if moving or abs(ticks - start.get(name, ticks)) > tolerance
        ]
        if off:
            raise DriverError(
                "follow: the axes must be at rest at the trajectory's set-point 0 (move_to "
                f"and wait_settled first); {', '.join(off)} are not; nothing was sent"
            )


class SetpointStream:
    """Sends a plan's set-points on ``link``, each at its due time."""

    def __init__(self, link: DynamixelLink) -> None:
        self._link = link

    def run(
        self,
        plan: SetpointPlan,
        clock: Clock,
        poll: Callable[[], StampedPositions],
        on_poll: Callable[[StampedPositions], None] | None,
    ) -> Followed:
        """For each set-point: sleep on ``clock`` until it is due, one SYNC_WRITE of its
        registers, one ``poll``, then ``on_poll``. Ended at the last poll's reply."""
        period = plan.trajectory.period_s
        ids = plan.motor_ids
        started = clock.now()
        sent: list[float] = []
        polls: list[StampedPositions] = []
        for k, row in enumerate(plan.registers.tolist()):
            wait = started + k * period - clock.now()
            if wait > 0:
                clock.sleep(wait)
            sent.append(clock.now())
            self._link.sync_write_items(SETPOINT_ITEMS, dict(zip(ids, row, strict=True)))
            polls.append(poll())
            if on_poll is not None:
                on_poll(polls[-1])
        tracking = tracking_error(plan.trajectory, started, polls)
        return Followed(started, tuple(sent), polls, tracking, polls[-1].reply_s)
