"""Coordinated multi-axis motion: a `Trajectory` of streamed set-points, its checks, and
what following it returns (`Followed`), shared by every motor backend
(`drivers.base.MotorBus.follow`).

A trajectory is a path in joint space sampled at a steady rate: the axes are due at
set-point k ``k · period_s`` after the trajectory starts; between two set-points they
move along the straight line joining them (a path sampled finely enough is smooth).
The first and the last set-point are poses at rest: the planner's time law starts and
ends at zero velocity. A backend streams the set-points (one write for all axes per
period, interleaved with one position poll), each axis's profile set so that the motors
follow without stopping.

The whole trajectory is checked before anything is sent (`check_trajectory`): every
set-point finite and inside its axis's limits, every axis's velocity between two
set-points within its configured velocity and every change of velocity within its
configured acceleration (both with `RATE_MARGIN`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from drivers.errors import DriverError, LimitError
from drivers.values import StampedPositions

#: Relative slack on the configured velocity and acceleration when a trajectory is
#: checked (a planner's time law meets them exactly; rounding must not refuse it).
RATE_MARGIN = 1e-6
#: Seconds a backend waits, after sending the last set-point, for the axes to settle
#: there before it holds them and raises `MotionTimeout`.
SETTLE_TIMEOUT_S = 5.0


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Set-points (K, A) rad for ``axes``, one every ``period_s`` seconds (K ≥ 2)."""

    axes: tuple[str, ...]
    period_s: float
    goals: NDArray[np.float64]

    def __post_init__(self) -> None:
        goals = np.array(self.goals, dtype=np.float64)
        if goals.ndim != 2 or goals.shape[1] != len(self.axes) or len(goals) < 2:
            raise DriverError(
                f"trajectory: expected set-points of shape (K ≥ 2, {len(self.axes)}), "
                f"got {goals.shape}; nothing was sent"
            )
        if not (math.isfinite(self.period_s) and self.period_s > 0):
            raise DriverError(f"trajectory: period {self.period_s!r} s is not positive")
        goals.setflags(write=False)
        object.__setattr__(self, "goals", goals)

    def __len__(self) -> int:
        return len(self.goals)

    @property
    def duration_s(self) -> float:
        """Seconds from the first set-point to the last."""
        return (len(self.goals) - 1) * self.period_s

    def velocities(self) -> NDArray[np.float64]:
        """(K − 1, A) rad/s: each axis's velocity between consecutive set-points."""
        return np.asarray(np.diff(self.goals, axis=0) / self.period_s, dtype=np.float64)

    def at(self, t: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """Where the path is (…, A) rad at ``t`` s after its start (the set-points joined
        by straight lines; the first before the start, the last after the end)."""
        times = np.asarray(t, dtype=np.float64)
        u = np.clip(times / self.period_s, 0.0, len(self.goals) - 1.0)
        k = np.minimum(np.floor(u).astype(np.int64), len(self.goals) - 2)
        w = (u - k)[..., None]
        return np.asarray((1.0 - w) * self.goals[k] + w * self.goals[k + 1], dtype=np.float64)


@dataclass(frozen=True)
class Followed:
    """What `MotorBus.follow` did: ``started_s`` the clock's time at which set-point 0
    was due (the trajectory's origin: set-point k due at ``started_s + k · period_s``),
    ``sent_s`` (K,) when each set-point's write left, ``polls`` the stamped polls made
    along the way (one per period), ``tracking_rad`` the largest distance (rad, any
    axis) between a poll and the path at the poll's middle, and ``ended_s`` when the
    last poll's reply arrived."""

    started_s: float
    sent_s: tuple[float, ...]
    polls: list[StampedPositions] = field(default_factory=list)
    tracking_rad: float = 0.0
    ended_s: float = 0.0


def tracking_error(
    trajectory: Trajectory, started_s: float, polls: Sequence[StampedPositions]
) -> float:
    """The largest distance (rad, over ``polls`` and the trajectory's axes) between a
    poll's position and the path at the poll's middle (``started_s``: the origin)."""
    if not polls:
        return 0.0
    middles = np.array([p.middle_s for p in polls]) - started_s
    read = np.array([[p.positions[n] for n in trajectory.axes] for p in polls])
    return float(np.max(np.abs(read - trajectory.at(middles))))


def check_trajectory(
    trajectory: Trajectory,
    limits: Mapping[str, tuple[float, float]],
    top_velocity: Mapping[str, float],
    top_acceleration: Mapping[str, float],
) -> None:
    """`DriverError` for an unknown axis, `LimitError` for a set-point outside its
    axis's limits or not finite, or for a velocity or a change of velocity above the
    axis's configured one (`RATE_MARGIN`); sends nothing."""
    for name in trajectory.axes:
        if name not in limits:
            raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(limits)}")
    goals = trajectory.goals
    lo = np.array([limits[n][0] for n in trajectory.axes])
    hi = np.array([limits[n][1] for n in trajectory.axes])
    bad = ~(np.isfinite(goals) & (goals >= lo) & (goals <= hi))
    if bad.any():
        k, j = (int(x) for x in np.argwhere(bad)[0])
        raise LimitError(
            f"axis {trajectory.axes[j]!r}: set-point {k} ({goals[k, j]!r} rad) is outside its "
            f"limits [{lo[j]:.6f}, {hi[j]:.6f}] rad; nothing was sent"
        )
    v = trajectory.velocities()
    a = np.diff(np.concatenate([np.zeros((1, v.shape[1])), v, np.zeros((1, v.shape[1]))]), axis=0)
    a /= trajectory.period_s
    for what, rates, tops, unit in (
        ("velocity", v, top_velocity, "rad/s"),
        ("acceleration", a, top_acceleration, "rad/s²"),
    ):
        top = np.array([tops[n] for n in trajectory.axes]) * (1.0 + RATE_MARGIN)
        over = np.abs(rates) > top
        if over.any():
            k, j = (int(x) for x in np.argwhere(over)[0])
            raise LimitError(
                f"axis {trajectory.axes[j]!r}: the trajectory's {what} at set-point {k} "
                f"({abs(rates[k, j]):.6g} {unit}) is above its configured {what} "
                f"({top[j] / (1.0 + RATE_MARGIN):.6g} {unit}); nothing was sent"
            )
