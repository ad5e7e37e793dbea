"""Where the simulated joints are along a motion: a trapezoidal profile per axis (rest to
rest, `profile_position`), or a streamed trajectory followed ideally (`JointPath`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drivers.trajectory import Trajectory
from gonio.types import FloatArray


def profile_position(
    start: FloatArray, goal: FloatArray, v: FloatArray, a: FloatArray, elapsed: float
) -> FloatArray:
    """Where trapezoidal profiles (rest to rest, per axis) from ``start`` to ``goal`` are
    after ``elapsed`` seconds (rad); at the goal once each profile has ended."""
    d = np.abs(goal - start)
    sign = np.sign(goal - start)
    t_acc = np.minimum(v / a, np.sqrt(d / a))  # time spent accelerating
    v_peak = a * t_acc
    cruise = np.where(v_peak > 0, d / np.where(v_peak > 0, v_peak, 1.0) - t_acc, 0.0)
    total = 2.0 * t_acc + cruise
    t = np.minimum(elapsed, total)
    accelerating = 0.5 * a * t * t
    cruising = 0.5 * a * t_acc**2 + v_peak * (t - t_acc)
    braking = d - 0.5 * a * (total - t) ** 2
    s = np.where(t < t_acc, accelerating, np.where(t < t_acc + cruise, cruising, braking))
    return np.asarray(np.where(t >= total, goal, start + sign * s), dtype=np.float64)


def profile_duration(start: FloatArray, goal: FloatArray, v: FloatArray, a: FloatArray) -> float:
    """Seconds until every trapezoidal profile (rest to rest) of `profile_position` ends."""
    d = np.abs(goal - start)
    t_acc = np.minimum(v / a, np.sqrt(d / a))
    v_peak = a * t_acc
    cruise = np.where(v_peak > 0, d / np.where(v_peak > 0, v_peak, 1.0) - t_acc, 0.0)
    return float(np.max(2.0 * t_acc + cruise, initial=0.0))


@dataclass(frozen=True, eq=False)
class JointPath:
    """Every axis following ``path`` (set-points over all the bus's axes, rad, joined by
    straight lines) from ``started_s`` on the clock; ``before`` (A,) is the sign of each
    axis's last motion before it (for backlash)."""

    path: Trajectory
    started_s: float
    before: FloatArray

    @property
    def end_s(self) -> float:
        """When the path reaches its last set-point (s on the clock)."""
        return self.started_s + self.path.duration_s

    @property
    def moved(self) -> np.ndarray:
        """(A,) whether each axis moves along the path."""
        return np.asarray(np.any(np.diff(self.path.goals, axis=0) != 0, axis=0))

    def at(self, t: FloatArray | float) -> FloatArray:
        """Positions (…, A) rad at clock time ``t`` (the first set-point before the start,
        the last after the end)."""
        return self.path.at(np.asarray(t, dtype=np.float64) - self.started_s)

    def direction_at(self, t: FloatArray | float) -> FloatArray:
        """(…, A) the sign of each axis's last motion up to clock time ``t``."""
        goals = self.path.goals
        step = np.sign(np.diff(goals, axis=0))  # (K − 1, A)
        k = np.arange(len(step))[:, None]
        last = np.maximum.accumulate(np.where(step != 0, k, -1), axis=0)
        taken = np.take_along_axis(step, np.maximum(last, 0), axis=0)
        directions = np.where(last >= 0, taken, self.before)
        u = (np.asarray(t, dtype=np.float64) - self.started_s) / self.path.period_s
        index = np.clip(np.floor(u), 0, len(step) - 1).astype(np.int64)
        out = np.where((u > 0)[..., None], directions[index], self.before)
        return np.asarray(out, dtype=np.float64)
