"""Streaming a trajectory's set-points to X-series motors (`DynamixelBus.follow`).

Per period one SYNC_WRITE of Profile Acceleration, Profile Velocity and Goal Position
(addresses 108-119, contiguous) for every axis of the trajectory, then one poll. The
motors run velocity-based profiles, and a new goal re-plans the profile from the
present position and velocity, so the registers of set-point k are chosen for the
motor to run along the path without braking (`setpoint_registers`):

* the goal is a look-ahead set-point, `lookahead` periods on, but never past a turning
  point of its axis or the last set-point (every goal is a set-point: inside the limits);
* the profile velocity is the path's speed at set-point k + 1 (the mean of the straight
  segments around it, the slope of the smooth time law the set-points sample), at
  least one register step (0 means "unlimited");
* the profile acceleration is that speed's change over one period, but at least what
  keeps the braking distance short of the look-ahead goal (the motor cruises), rounded
  up to the register step and at most the configured one;
* from the second set-point on, the last poll corrects both (`SetpointPlan.corrected`):
  the speed makes up the distance the motors were behind the path (or ahead) in
  `CATCH_UP_PERIODS` periods, and the acceleration reaches that speed within a period
  from the velocity the last two polls show.

Tracking: a motor that can change its speed by the path's change within one period
stays within about a · period² / 8 of the straight segments (the smooth curve's
distance from its chords), plus an encoder tick and what the one-period-old feedback
leaves at a turn; the contract suite states the bound on the emulated X series, and
benchmarks/trajectory_bus.py measures it on the rehearsal path.
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
#: A motor behind the path (or ahead) at a poll makes the distance up in this many
#: periods (`SetpointPlan.corrected`): the poll is a period old when it is used.
CATCH_UP_PERIODS = 2.0
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


def setpoint_registers(
    trajectory: Trajectory, axes: Sequence[AxisConfig]
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The registers (K, A, 3: Profile Acceleration, Profile Velocity, Goal Position) of
    each set-point for the trajectory's axes ``axes`` (the module docstring), the speed
    they aim at (K, A, in velocity steps, before rounding) and the sign of each goal's
    direction from its set-point (K, A). The trajectory is checked already
    (`drivers.trajectory.check_trajectory`)."""
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
    speed = np.abs(aim) * gear / RAD_S_PER_VELOCITY_UNIT
    speed_reg = np.clip(np.round(speed), 1, configured[:, 0])
    direction = np.array([a.direction for a in axes])
    zero = np.array([a.zero_offset_rad for a in axes])
    ticks = np.round(direction * (target - zero) * gear / RAD_PER_TICK)
    limits = np.array([a.tick_limits() for a in axes])
    ticks = np.clip(ticks, limits[:, 0], limits[:, 1])
    registers = np.stack([accel_reg, speed_reg, ticks], axis=-1).astype(np.int64)
    return registers, speed, np.sign(target - goals)


@dataclass(frozen=True, eq=False)
class SetpointPlan:
    """A checked trajectory for ``axes``: its set-points' registers (K, A, 3), the speed
    each aims at (K, A, velocity steps) and its goal's direction (K, A) (`setpoint_registers`)."""

    trajectory: Trajectory
    axes: tuple[AxisConfig, ...]
    registers: NDArray[np.int64]
    speed: NDArray[np.float64]
    toward: NDArray[np.float64]

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
        return cls(trajectory, named, *setpoint_registers(trajectory, named))

    def corrected(
        self, k: int, behind: NDArray[np.float64], velocity: NDArray[np.float64]
    ) -> NDArray[np.int64]:
        """Set-point ``k``'s registers (A, 3), each axis's speed raised by what makes up
        ``behind`` (A, rad: the path minus the last poll) in `CATCH_UP_PERIODS` periods
        (lowered when ahead), and its acceleration raised to what reaches that speed
        within one period from ``velocity`` (A, rad/s: the motors' last, polled)."""
        row: NDArray[np.int64] = self.registers[k].copy()
        gear = np.array([a.gear_ratio for a in self.axes])
        top = np.array([a.profile_registers() for a in self.axes])  # (A, 2) velocity, accel
        period = self.trajectory.period_s
        extra = self.toward[k] * behind / (CATCH_UP_PERIODS * period)  # rad/s
        speed = np.clip(self.speed[k] + extra * gear / RAD_S_PER_VELOCITY_UNIT, 1.0, top[:, 0])
        change = np.abs(self.toward[k] * speed * RAD_S_PER_VELOCITY_UNIT / gear - velocity)
        needed = np.ceil(change / period * gear / RAD_S2_PER_ACCELERATION_UNIT - 1e-9)
        row[:, 1] = np.round(speed)
        row[:, 0] = np.clip(np.maximum(row[:, 0], needed), 1, top[:, 1])
        return row

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
            a.name: a.clamp_ticks(a.to_ticks(float(x)))
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
        path = plan.trajectory
        for k in range(len(path)):
            row = plan.registers[k]
            if len(polls) >= 2:  # make up the distance the last poll was behind the path
                before, last = (
                    np.array([p.positions[a.name] for a in plan.axes]) for p in polls[-2:]
                )
                velocity = (last - before) / (polls[-1].middle_s - polls[-2].middle_s)
                behind = path.at(polls[-1].middle_s - started) - last
                row = plan.corrected(k, behind, velocity)
            wait = started + k * period - clock.now()
            if wait > 0:
                clock.sleep(wait)
            sent.append(clock.now())
            self._link.sync_write_items(SETPOINT_ITEMS, dict(zip(ids, row.tolist(), strict=True)))
            polls.append(poll())
            if on_poll is not None:
                on_poll(polls[-1])
        tracking = tracking_error(plan.trajectory, started, polls)
        return Followed(started, tuple(sent), polls, tracking, polls[-1].reply_s)
