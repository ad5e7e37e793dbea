"""Choosing one inverse-kinematics solution per target along an ordered path.

Where a pair has several joint-angle solutions, the plan takes, target after target,
the sequence that minimizes the total travel time (a Viterbi pass over the K candidates
of each target: exact for the given order).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gonio.types import BoolArray, FloatArray

TravelTime = Callable[[FloatArray, FloatArray], FloatArray]


def choose(
    candidates: FloatArray, usable: BoolArray, start: FloatArray, travel: TravelTime
) -> tuple[FloatArray, FloatArray]:
    """(angles (N, A), travel time (N,) into each target) along the given order.

    ``candidates`` (N, K, A) with ``usable`` (N, K) (every target has at least one).
    The loop runs over targets (each step is a K × K numpy operation): the choice at a
    target depends on the one before it.
    """
    n, k, _ = candidates.shape
    cost = np.where(usable[0], travel(start, candidates[0]), np.inf)
    back = np.zeros((n, k), dtype=np.int64)
    for i in range(1, n):
        step = travel(candidates[i - 1][:, None, :], candidates[i][None, :, :])  # (K, K)
        total = cost[:, None] + step
        back[i] = np.argmin(total, axis=0)
        cost = np.where(usable[i], total[back[i], np.arange(k)], np.inf)
    pick = np.empty(n, dtype=np.int64)
    pick[-1] = int(np.argmin(cost))
    for i in range(n - 1, 0, -1):
        pick[i - 1] = back[i, pick[i]]
    angles = candidates[np.arange(n), pick]
    previous = np.vstack([start[None, :], angles[:-1]])
    return np.asarray(angles, dtype=np.float64), np.asarray(
        travel(previous, angles), dtype=np.float64
    )
