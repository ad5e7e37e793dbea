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

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from gonio import progress
from gonio.rig.travel import TravelModel
from gonio.types import BoolArray, FloatArray

TravelTime = Callable[[FloatArray, FloatArray], FloatArray]
#: Pose pairs the vectorized relaxed time handles at once (memory: × K² × A floats).
CHUNK = 20_000


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

    def scalar(self) -> Callable[[int, int], float]:
        """The relaxed time of two nodes as a Python float (for the local search)."""
        time_of = self.model.scalar()
        lists = [
            [p for p, ok in zip(row, oks, strict=True) if ok]
            for row, oks in zip(self.poses.tolist(), self.usable.tolist(), strict=True)
        ]

        def cost(u: int, v: int) -> float:
            best = math.inf
            for p in lists[u]:
                for q in lists[v]:
                    t = time_of(p, q)
                    if t < best:
                        best = t
            return best

        return cost

    def flat(self) -> tuple[FloatArray, np.ndarray]:
        """(every usable pose (P, A), the node each belongs to (P,))."""
        node, slot = np.nonzero(self.usable)
        return self.poses[node, slot], node

    def neighbour_lists(self, k: int, scale: float) -> tuple[np.ndarray, FloatArray]:
        """(indices (N + 1, k), relaxed times (N + 1, k)): each node's nearest others in
        relaxed time, nearest first, equal times in index order (−1 and inf pad a short
        row). Candidates: the k + 1 + K nearest poses of each of a node's poses in a k-d
        tree (Chebyshev in coordinates scaled by each axis's reach in ``scale`` seconds),
        ranked by the exact relaxed time."""
        m = len(self.poses)
        k = min(k, m - 1)
        if k <= 0:
            return np.zeros((m, 0), dtype=np.int64), np.zeros((m, 0))
        flat, owner = self.flat()
        scaled = flat / np.maximum(self.model.reach(scale), 1e-300)
        q = min(k + 1 + int(self.usable.sum(axis=1).max()), len(flat))
        _, idx = cKDTree(scaled).query(scaled, k=q, p=np.inf)
        u = np.repeat(owner, q)
        v = owner[np.asarray(idx, dtype=np.int64).reshape(-1)]
        keep = u != v
        pair = np.unique(u[keep] * m + v[keep])  # sorted by u, then v
        u, v = pair // m, pair % m
        t = self.times(u, v)
        by = np.lexsort((v, t, u))  # by node, then time, then index
        u, v, t = u[by], v[by], t[by]
        first = np.searchsorted(u, np.arange(m))
        rank = np.arange(len(u)) - first[u]
        out = np.full((m, k), -1, dtype=np.int64)
        times = np.full((m, k), np.inf)
        take = rank < k
        out[u[take], rank[take]] = v[take]
        times[u[take], rank[take]] = t[take]
        return out, times


def choose(
    candidates: FloatArray, usable: BoolArray, start: FloatArray, travel: TravelTime
) -> tuple[FloatArray, FloatArray]:
    """(angles (N, A), travel time (N,) into each target) along the given order.

    ``candidates`` (N, K, A) with ``usable`` (N, K) (every target has at least one).
    Only usable candidates are ever returned. The moves between consecutive targets'
    candidates are computed `CHUNK` targets at a time (CHUNK, K′, K′) over the K′ usable
    slots packed first (memory: O(N · K′) for the back pointers, whatever N); the
    recursion (each choice depends on the one before) runs over Python floats.
    """
    n = len(candidates)
    if n == 0:
        return np.zeros((0, candidates.shape[2])), np.zeros(0)
    k = max(int(usable.sum(axis=1).max()), 1)
    slots = np.argsort(~usable, axis=1, kind="stable")[:, :k]  # usable ones first
    packed = np.take_along_axis(candidates, slots[:, :, None], axis=1)
    ok = np.take_along_axis(usable, slots, axis=1)
    cost = np.where(ok[0], travel(start, packed[0]), np.inf).tolist()
    back = np.zeros((max(n - 1, 0), k), dtype=np.int64)  # best slot of i given i + 1's
    span = range(k)
    with progress.stage("choosing the poses", n) as shown:
        for lo in range(0, n - 1, CHUNK):
            hi = min(lo + CHUNK, n - 1)
            steps = np.where(
                ok[lo:hi, :, None] & ok[lo + 1 : hi + 1, None, :],
                travel(packed[lo:hi, :, None, :], packed[lo + 1 : hi + 1, None, :, :]),
                np.inf,
            ).tolist()  # (chunk, K′, K′): from slot a of target i to slot b of target i + 1
            best_from = []
            for step in steps:
                new = []
                row = []
                for b in span:
                    best, arg = math.inf, 0
                    for a in span:
                        t = cost[a] + step[a][b]
                        if t < best:
                            best, arg = t, a
                    new.append(best)
                    row.append(arg)
                best_from.append(row)
                cost = new
            back[lo:hi] = best_from
            shown.advance(hi - lo)
    chosen = np.empty(n, dtype=np.int64)
    last = min(span, key=lambda b: cost[b])
    chosen[n - 1] = last
    pointer = back.item
    for i in range(n - 2, -1, -1):
        last = pointer(i, last)
        chosen[i] = last
    angles = packed[np.arange(n), chosen]
    previous = np.vstack([start[None, :], angles[:-1]])
    return np.asarray(angles, dtype=np.float64), np.asarray(
        travel(previous, angles), dtype=np.float64
    )
