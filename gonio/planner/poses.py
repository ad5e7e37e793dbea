"""The inverse-kinematics branches of the targets: the relaxed any-branch move time, and
the exact choice of one solution per target along an order.

Where a pair has several usable joint-angle solutions (mirror images, a rotation stage
a turn either way), the best path depends on the order and on the solutions together:

- `Relaxed`: the move time between two targets relaxed to the shortest move between
  any of their usable solutions. Every path with any choice of solutions is at least as
  long as the same order in the relaxed time, so an order found on it is a good order
  for some choice, and a lower bound on it bounds every choice.
- `choose`: for a given order, the sequence of solutions with the least total travel
  (Viterbi over the K candidates of each target: exact for that order).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gonio import progress
from gonio.planner.jit import compiled
from gonio.planner.nearest import nearest_others
from gonio.rig import TravelModel
from gonio.types import BoolArray, FloatArray

TravelTime = Callable[[FloatArray, FloatArray], FloatArray]
#: Pose pairs the vectorized relaxed time handles at once (memory: × K² × A floats).
CHUNK = 4096


@dataclass(frozen=True)
class Relaxed:
    """The usable solutions of n targets and the start, packed: ``poses`` (N + 1, K, A)
    with ``usable`` (N + 1, K), usable ones first; node n is the start (one pose)."""

    model: TravelModel
    poses: FloatArray
    usable: BoolArray

    @classmethod
    def of(
        cls, model: TravelModel, candidates: FloatArray, usable: BoolArray, start: FloatArray
    ) -> Relaxed:
        """From the rig's candidates (N, K, A) and their usability (N, K) (each target
        has at least one usable) and the start pose (A,)."""
        a = candidates.shape[2]
        k = max(int(usable.sum(axis=1).max(initial=1)), 1)
        first = np.argsort(~usable, axis=1, kind="stable")[:, :k]  # usable ones first
        poses = np.take_along_axis(candidates, first[:, :, None], axis=1)
        ok = np.take_along_axis(usable, first, axis=1)
        poses = np.where(ok[:, :, None], poses, poses[:, :1, :])  # unusable: a copy
        start_row = np.broadcast_to(np.asarray(start, dtype=np.float64), (1, k, a))
        start_ok = np.zeros((1, k), dtype=np.bool_)
        start_ok[0, 0] = True
        return cls(
            model,
            np.ascontiguousarray(np.concatenate([poses, start_row]), dtype=np.float64),
            np.concatenate([ok, start_ok]),
        )

    @property
    def n(self) -> int:
        """Targets (the start not counted)."""
        return len(self.poses) - 1

    def times(self, u: np.ndarray, v: np.ndarray) -> FloatArray:
        """Relaxed move times (s) between nodes ``u`` and ``v`` (P,), vectorized."""
        out = np.empty(len(u), dtype=np.float64)
        for lo in range(0, len(u), CHUNK):
            pu, pv = u[lo : lo + CHUNK], v[lo : lo + CHUNK]
            t = self.model.time(self.poses[pu][:, :, None, :], self.poses[pv][:, None, :, :])
            ok = self.usable[pu][:, :, None] & self.usable[pv][:, None, :]
            out[lo : lo + CHUNK] = np.where(ok, t, np.inf).min(axis=(1, 2))
        return out

    def flat(self) -> tuple[FloatArray, np.ndarray]:
        """(every usable pose (P, A), the node each belongs to (P,))."""
        node, slot = np.nonzero(self.usable)
        return self.poses[node, slot], node

    def neighbour_lists(self, k: int) -> tuple[np.ndarray, FloatArray]:
        """(indices (N + 1, k), relaxed times (N + 1, k)): each node's nearest others in
        relaxed time, nearest first, equal times in index order (−1 and inf pad a short
        row; exact: `gonio.planner.nearest.nearest_others` over the usable poses)."""
        flat, owner = self.flat()
        return nearest_others(self.model, flat, owner, k)


def choose(
    candidates: FloatArray, usable: BoolArray, start: FloatArray, travel: TravelTime
) -> tuple[FloatArray, FloatArray]:
    """(angles (N, A), travel time (N,) into each target) along the given order.

    ``candidates`` (N, K, A) with ``usable`` (N, K) (every target has at least one).
    Only usable candidates are ever returned. The moves between consecutive targets'
    candidates are computed `CHUNK` targets at a time (CHUNK, K′, K′) over the K′ usable
    slots packed first (memory: O(N · K′) for the back pointers, whatever N); the
    recursion (each choice depends on the one before) is compiled.
    """
    n = len(candidates)
    if n == 0:
        return np.zeros((0, candidates.shape[2])), np.zeros(0)
    k = max(int(usable.sum(axis=1).max()), 1)
    slots = np.argsort(~usable, axis=1, kind="stable")[:, :k]  # usable ones first
    packed = np.take_along_axis(candidates, slots[:, :, None], axis=1)
    ok = np.take_along_axis(usable, slots, axis=1)
    cost = np.where(ok[0], travel(start, packed[0]), np.inf)
    back = np.zeros((max(n - 1, 0), k), dtype=np.int64)  # best slot of i given i + 1's
    with progress.stage("choosing the poses", n) as shown:
        for lo in range(0, n - 1, CHUNK):
            hi = min(lo + CHUNK, n - 1)
            steps = np.where(
                ok[lo:hi, :, None] & ok[lo + 1 : hi + 1, None, :],
                travel(packed[lo:hi, :, None, :], packed[lo + 1 : hi + 1, None, :, :]),
                np.inf,
            )  # (chunk, K′, K′): from slot a of target i to slot b of target i + 1
            _forward(np.ascontiguousarray(steps, dtype=np.float64), cost, back[lo:hi])
            shown.advance(hi - lo)
    chosen = _backward(back, int(np.argmin(cost)))
    angles = packed[np.arange(n), chosen]
    previous = np.vstack([start[None, :], angles[:-1]])
    return np.asarray(angles, dtype=np.float64), np.asarray(
        travel(previous, angles), dtype=np.float64
    )


@compiled
def _forward(steps: FloatArray, cost: FloatArray, back: np.ndarray) -> None:
    """Viterbi's forward pass over ``steps`` (C, K, K): ``cost`` (K,) the least travel
    to each slot of the current target, updated in place; ``back`` (C, K) the best slot
    before each (the first of equal ones)."""
    k = len(cost)
    new = np.empty(k)
    for s in range(len(steps)):
        for b in range(k):
            best, arg = np.inf, 0
            for a in range(k):
                t = cost[a] + steps[s, a, b]
                if t < best:
                    best, arg = t, a
            new[b] = best
            back[s, b] = arg
        cost[:] = new


@compiled
def _backward(back: np.ndarray, last: int) -> np.ndarray:
    """The slots chosen, from the last target's ``last`` back through ``back``."""
    n = len(back) + 1
    chosen = np.empty(n, dtype=np.int64)
    chosen[n - 1] = last
    for i in range(n - 2, -1, -1):
        last = back[i, last]
        chosen[i] = last
    return chosen
