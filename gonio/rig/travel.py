"""`TravelModel`: how long the rig's axes take to move between two poses.

Each axis follows a trapezoidal profile (accelerate at a, cruise at v, decelerate at a)
and all axes start together, so a move takes its slowest axis's time:

    t_j(d) = 2 √(d / a_j)            if d < v_j² / a_j  (never reaches cruise speed)
           = d / v_j + v_j / a_j      otherwise

with d = |Δθ_j| (rad), v in rad/s, a in rad/s². Each t_j is increasing, concave and
zero at zero, so the move time is a metric on joint space (the triangle inequality
holds), which the ordering's lower bound relies on.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gonio.types import ArrayLike, FloatArray


@dataclass(frozen=True)
class TravelModel:
    """Per-axis maximum velocity (rad/s) and acceleration (rad/s²), shape (A,)."""

    velocity: FloatArray
    acceleration: FloatArray

    def __post_init__(self) -> None:
        v = np.asarray(self.velocity, dtype=np.float64)
        a = np.asarray(self.acceleration, dtype=np.float64)
        if v.shape != a.shape or v.ndim != 1 or not v.size or np.any(v <= 0) or np.any(a <= 0):
            raise ValueError(
                "velocity and acceleration must be positive, one per axis (one axis at least)"
            )
        object.__setattr__(self, "velocity", v)
        object.__setattr__(self, "acceleration", a)

    def time(self, p: ArrayLike, q: ArrayLike) -> FloatArray:
        """Move time (s) from poses p to q (..., A), broadcast over leading axes.

        Computed axis by axis (each a long row, where the poses' short last axis would
        make every numpy call loop over A values), the slowest axis kept.
        """
        start = np.asarray(p, dtype=np.float64)
        end = np.asarray(q, dtype=np.float64)
        v_all, a_all = self.velocity, self.acceleration
        knee, ramp = v_all * v_all / a_all, v_all / a_all
        worst: FloatArray | None = None
        for j, (v, a) in enumerate(zip(v_all, a_all, strict=True)):
            d = np.abs(end[..., j] - start[..., j])
            t = np.where(d < knee[j], 2.0 * np.sqrt(d / a), d / v + ramp[j])
            worst = t if worst is None else np.maximum(worst, t)
        assert worst is not None  # one axis at least (__post_init__ says so)
        return np.asarray(worst, dtype=np.float64)

    def reach(self, t: float | FloatArray) -> FloatArray:
        """Per-axis largest |Δθ| (rad) covered within t seconds: t(p, q) ≤ t exactly when
        |q_j − p_j| ≤ reach(t)_j on every axis. ``t`` a number, or times (..., 1) for
        reaches (..., A)."""
        v, a = self.velocity, self.acceleration
        return np.asarray(
            np.where(t < 2.0 * v / a, a * t * t / 4.0, v * (t - v / a)), dtype=np.float64
        )

    def ramp(self, velocity: ArrayLike) -> tuple[float, FloatArray]:
        """(time s, per-axis distance rad (A,)) to reach the per-axis constant
        ``velocity`` (A,) (rad/s) from rest along a straight line in joint space, every
        axis accelerating together: t = max_j |v_j| / a_j, d_j = |v_j| t / 2 (the same to
        stop from it)."""
        v = np.abs(np.asarray(velocity, dtype=np.float64))
        t = float(np.max(v / self.acceleration))
        return t, np.asarray(0.5 * v * t, dtype=np.float64)

    def scalar(self) -> Callable[[Sequence[float], Sequence[float]], float]:
        """`time` for two single poses as plain Python floats: the local search calls it
        millions of times, where a numpy call's overhead would dominate."""
        axes = [
            (float(v), float(a), float(v * v / a), float(v / a))
            for v, a in zip(self.velocity, self.acceleration, strict=True)
        ]
        sqrt = math.sqrt

        def time(p: Sequence[float], q: Sequence[float]) -> float:
            worst = 0.0
            for (v, a, knee, ramp), x, y in zip(axes, p, q, strict=True):
                d = x - y if x > y else y - x
                t = 2.0 * sqrt(d / a) if d < knee else d / v + ramp
                if t > worst:
                    worst = t
            return worst

        return time
