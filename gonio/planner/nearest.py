"""Nearest poses by travel time (`gonio.rig.travel.TravelModel`), exactly, equal times in
index order, so independent of how they are found:

- `nearest_neighbour`: the nearest-neighbour order, from the start pose always to the
  nearest target not yet visited;
- `nearest_others`: each node's k nearest others (a node may have several poses: the
  relaxed any-branch time), the local search's neighbour lists.

Both search a k-d tree over the poses (compiled): a subtree's bounding box bounds the
time to every pose inside (each axis's time grows with its distance), so a box is
skipped when some axis's distance to it exceeds what that axis covers in the time to
beat (`TravelModel.reach`, widened by a hair: never a box that could hold a tie).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from gonio import progress
from gonio.planner.jit import compiled
from gonio.planner.moves import axis_time
from gonio.planner.search import Metric
from gonio.rig import TravelModel
from gonio.types import BoolArray, FloatArray

Ints = npt.NDArray[np.int64]
#: A k-d tree over poses (`_build`).
Tree = tuple[Ints, Ints, Ints, FloatArray, FloatArray, Ints, Ints, FloatArray, Ints, Ints]

#: Targets in a leaf of the tree (at most).
LEAF = 8
#: Steps of the construction between two updates of the progress display.
CHUNK = 1 << 14


def nearest_neighbour(model: TravelModel, points: FloatArray, start: FloatArray) -> np.ndarray:
    """Indices of ``points`` (N, A) in nearest-neighbour order from ``start`` (A,)."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    n = len(points)
    order = np.empty(n, dtype=np.int64)
    if n == 0:
        return order
    axes = Metric.of(model, points[:1]).axes
    tree = _build(points, axes[0].copy(), LEAF)
    left = tree[5].copy()  # targets left in each subtree (its count at first)
    visited = np.zeros(n, dtype=np.bool_)
    here = np.asarray(start, dtype=np.float64).copy()
    with progress.stage("nearest-neighbour construction", n) as shown:
        for lo in range(0, n, CHUNK):
            hi = min(lo + CHUNK, n)
            _walk(points, axes, tree, left, visited, here, order, lo, hi)
            shown.advance(hi - lo)
    return order


def nearest_others(
    model: TravelModel, poses: FloatArray, owner: np.ndarray, k: int
) -> tuple[np.ndarray, FloatArray]:
    """Each node's ``k`` nearest other nodes by travel time, nearest first, equal times
    in index order: (nodes (M, k), times (M, k) s; −1 and inf pad a short row).

    ``poses`` (P, A) with ``owner`` (P,) nondecreasing, the node of each (0..M-1, every
    node at least one pose); the time between two nodes is the shortest move between any
    of their poses (the relaxed any-branch time, `gonio.planner.poses.Relaxed`). Exact:
    a k-d tree over the poses, searched from each of a node's poses.
    """
    poses = np.ascontiguousarray(poses, dtype=np.float64)
    owner = np.ascontiguousarray(owner, dtype=np.int64)
    m = int(owner[-1]) + 1 if len(owner) else 0
    k = max(min(k, m - 1), 0)
    nodes = np.full((m, k), -1, dtype=np.int64)
    times = np.full((m, k), np.inf)
    if k == 0:
        return nodes, times
    axes = Metric.of(model, poses[:1]).axes
    first = np.searchsorted(owner, np.arange(m + 1))
    tree = _build(poses, axes[0].copy(), LEAF)
    _nearest_others(poses, owner, first, axes, tree, nodes, times)
    return nodes, times


@compiled
def _build(points: FloatArray, velocity: FloatArray, leaf: int) -> Tree:
    """The tree, node 0 its root: (perm (N,) the poses leaf by leaf; first (T,) and
    last (T,): each node's poses are perm[first:last]; low (T, A) and high (T, A): the
    corners of its box; count (T,) its poses; children (T, 2) (−1: a leaf); the cut
    (T,) and the axis (T,) it splits at; links (T + N,): each node's parent (−1: the
    root), then each pose's leaf). A node splits at the median of its widest axis in
    time (spread / velocity)."""
    n, a = points.shape
    nodes = 4 * (n // leaf + 1) + 1
    perm = np.arange(n)
    first = np.zeros(nodes, np.int64)
    last = np.zeros(nodes, np.int64)
    low = np.zeros((nodes, a))
    high = np.zeros((nodes, a))
    count = np.zeros(nodes, np.int64)
    children = np.full((nodes, 2), -1, np.int64)
    axis = np.zeros(nodes, np.int64)
    cut = np.zeros(nodes)
    parent = np.full(nodes, -1, np.int64)
    leaf_of = np.zeros(n, np.int64)
    stack = np.zeros(nodes, np.int64)
    first[0], last[0], used, top = 0, n, 1, 1
    while top > 0:
        top -= 1
        t = stack[top]
        lo, hi = first[t], last[t]
        count[t] = hi - lo
        low[t] = np.inf
        high[t] = -np.inf
        for k in range(lo, hi):
            for j in range(a):
                x = points[perm[k], j]
                low[t, j] = min(low[t, j], x)
                high[t, j] = max(high[t, j], x)
        if hi - lo <= leaf:
            for k in range(lo, hi):
                leaf_of[perm[k]] = t
            continue
        dim, widest = 0, -1.0
        for j in range(a):
            spread = (high[t, j] - low[t, j]) / velocity[j]
            if spread > widest:
                dim, widest = j, spread
        block = perm[lo:hi].copy()
        perm[lo:hi] = block[np.argsort(points[block, dim], kind="mergesort")]
        middle = lo + (hi - lo) // 2
        axis[t], cut[t] = dim, points[perm[middle], dim]
        for side in range(2):
            c = used
            used += 1
            first[c], last[c], parent[c] = (lo, middle, t) if side == 0 else (middle, hi, t)
            children[t, side] = c
            stack[top] = c
            top += 1
    links = np.concatenate((parent, leaf_of))
    return perm, first, last, low, high, count, children, cut, axis, links


@compiled
def _reach(axes: FloatArray, t: float, out: FloatArray) -> None:
    """Each axis's largest distance (rad) covered within t s (`TravelModel.reach`),
    widened by a hair so that rounding never skips a pose at exactly t."""
    for j in range(len(out)):
        v, a = axes[0, j], axes[1, j]
        r = a * t * t / 4.0 if t < 2.0 * v / a else v * (t - v / a)
        out[j] = r * (1.0 + 1e-9) + 1e-12


@compiled
def _outside(low: FloatArray, high: FloatArray, t: int, x: FloatArray, reach: FloatArray) -> bool:
    """Whether node t's box is farther from x than ``reach`` on some axis."""
    for j in range(len(x)):  # noqa: SIM110 (compiled code: a loop, not a generator)
        if low[t, j] - x[j] > reach[j] or x[j] - high[t, j] > reach[j]:
            return True
    return False


@compiled
def _time_within(axes: FloatArray, x: FloatArray, y: FloatArray, reach: FloatArray) -> float:
    """The move time x → y (s), or inf if farther than ``reach`` on some axis."""
    worst = 0.0
    for j in range(len(x)):
        d = x[j] - y[j] if x[j] > y[j] else y[j] - x[j]
        if d > reach[j]:
            return np.inf
        worst = max(worst, axis_time(axes, j, d))
    return worst


@compiled
def _push_children(tree: Tree, t: int, x: FloatArray, stack: Ints, top: int) -> int:
    """Push node t's children, the one on x's side of the cut on top."""
    children, cut, axis = tree[6], tree[7], tree[8]
    near, far = children[t, 0], children[t, 1]
    if x[axis[t]] >= cut[t]:
        near, far = far, near
    stack[top], stack[top + 1] = far, near
    return top + 2


@compiled
def _walk(
    points: FloatArray,
    axes: FloatArray,
    tree: Tree,
    left: Ints,
    visited: BoolArray,
    here: FloatArray,
    order: Ints,
    lo: int,
    hi: int,
) -> None:
    """Steps lo..hi-1 of the order from ``here`` (updated), targets taken out of the
    tree as they are visited (``left``, ``visited``)."""
    perm, first, last, low, high = tree[0], tree[1], tree[2], tree[3], tree[4]
    children, links = tree[6], tree[9]
    nodes = len(first)
    n, a = points.shape
    stack = np.zeros(256, np.int64)
    reach = np.empty(a)
    for step in range(lo, hi):
        best, best_i = np.inf, n
        reach[:] = np.inf
        stack[0], top = 0, 1
        while top > 0:
            top -= 1
            t = stack[top]
            if left[t] == 0 or _outside(low, high, t, here, reach):
                continue
            if children[t, 0] >= 0:
                top = _push_children(tree, t, here, stack, top)
                continue
            for k in range(first[t], last[t]):
                p = perm[k]
                if visited[p]:
                    continue
                time = _time_within(axes, here, points[p], reach)
                if time < best or (time == best and p < best_i):
                    best, best_i = time, p
                    _reach(axes, best, reach)
        order[step] = best_i
        visited[best_i] = True
        t = links[nodes + best_i]  # its leaf, then up to the root
        while t >= 0:
            left[t] -= 1
            t = links[t]
        here[:] = points[best_i]


@compiled
def _nearest_others(
    poses: FloatArray,
    owner: Ints,
    first_pose: Ints,
    axes: FloatArray,
    tree: Tree,
    nodes: Ints,
    times: FloatArray,
) -> None:
    """Fill each row of ``nodes`` and ``times`` (sorted by time, then node)."""
    perm, first, last, low, high, children = tree[0], tree[1], tree[2], tree[3], tree[4], tree[6]
    k = nodes.shape[1]
    stack = np.zeros(256, np.int64)
    reach = np.empty(poses.shape[1])
    for u in range(len(nodes)):
        row, rt = nodes[u], times[u]
        held = 0
        reach[:] = np.inf
        for x_at in range(first_pose[u], first_pose[u + 1]):
            x = poses[x_at]
            stack[0], top = 0, 1
            while top > 0:
                top -= 1
                t = stack[top]
                if _outside(low, high, t, x, reach):
                    continue
                if children[t, 0] >= 0:
                    top = _push_children(tree, t, x, stack, top)
                    continue
                for e in range(first[t], last[t]):
                    p = perm[e]
                    v = owner[p]
                    if v == u:
                        continue
                    time = _time_within(axes, x, poses[p], reach)
                    if time < np.inf:
                        bound = rt[k - 1]
                        held = _offer(row, rt, held, v, time)
                        if rt[k - 1] != bound:
                            _reach(axes, rt[k - 1], reach)


@compiled
def _offer(row: Ints, rt: FloatArray, held: int, v: int, t: float) -> int:
    """Offer node v at time t to a row sorted by (time, node) holding ``held`` entries
    (a node once, at its least time); returns the entries held after."""
    k = len(row)
    at = -1
    for e in range(held):
        if row[e] == v:
            at = e
    if at >= 0:
        if not t < rt[at]:
            return held
        for e in range(at, held - 1):  # take it out, to insert it again below
            row[e], rt[e] = row[e + 1], rt[e + 1]
        held -= 1
        row[held], rt[held] = -1, np.inf
    elif held == k and not (t < rt[k - 1] or (t == rt[k - 1] and v < row[k - 1])):
        return held
    e = min(held, k - 1)
    while e > 0 and (t < rt[e - 1] or (t == rt[e - 1] and v < row[e - 1])):
        row[e], rt[e] = row[e - 1], rt[e - 1]
        e -= 1
    row[e], rt[e] = v, t
    return min(held + 1, k)
