"""Ordering motor targets: a short open path from the start pose through every target.

The cost of a move is the rig's travel time (`gonio.rig.travel.TravelModel`, a metric on
joint space). The path starts at the given pose and ends anywhere.

- Construction: the given order (a serpentine over a grid) or nearest neighbour.
- Improvement: 2-opt and Or-opt (segments of 1 to 3 targets, either orientation) over
  neighbour lists with don't-look bits, until no move improves or a budget of improving
  moves is spent (`default_moves`: a count, so the result is the same on any machine);
  a wall-clock cap stays as a safety net, and when it binds the result says so, since
  the order then depends on the machine's speed.
- Lower bound: the exact minimum spanning tree of the travel-time graph over the start
  and the targets (any path through them is a spanning tree), found with Kruskal on the
  graph of moves up to a threshold time, raised until that graph is connected.

The local search is sequential by nature (each move changes the next one's costs), so
it runs as a Python loop over nodes with scalar costs; everything else is vectorized.
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from gonio.rig.travel import TravelModel
from gonio.types import FloatArray

Method = Literal["given", "nearest", "auto"]
#: Why the local search stopped: no improving move left, the move budget spent, or the
#: wall-clock cap reached (only the last depends on the machine).
Stop = Literal["converged", "move budget", "time cap"]

#: Neighbours per node the local search considers.
NEIGHBOURS = 10
#: Improvements smaller than this (s) are not moves: they would cycle on rounding.
EPSILON = 1e-9
#: Pairs the lower bound may hold in memory before it gives up on exactness.
MAX_PAIRS = 10_000_000
#: Added to every edge so that csgraph keeps zero-time moves (it drops explicit zeros).
TINY = 1e-300
#: The default budget of improving moves: this many per target, plus `MOVES_EXTRA`. The
#: shipped plans converge after at most 1.5 moves per target, a random given order of
#: uniform poses after at most 3, so the budget binds only on something unusual.
MOVES_PER_TARGET = 10
MOVES_EXTRA = 100


def default_moves(n: int) -> int:
    """The budget of improving moves for ``n`` targets when none is given."""
    return MOVES_PER_TARGET * n + MOVES_EXTRA


@dataclass(frozen=True)
class Ordering:
    """``order`` indexes the targets in visiting order; times in seconds (moves only)."""

    order: np.ndarray
    travel_s: float  # the ordered path from the start
    constructed_s: float  # the constructive order before improvement
    given_s: float  # the targets in the order given
    lower_bound_s: float  # the minimum spanning tree over the start and the targets
    lower_bound_exact: bool  # False if memory forced a weaker bound
    moves: int  # improving moves applied
    converged: bool  # no improving move left
    stopped: Stop = "converged"  # why the improvement ended
    max_moves: int = 0  # the budget of improving moves it had
    order_wall_s: float = 0.0  # wall time spent constructing and improving
    bound_wall_s: float = 0.0  # wall time spent on the lower bound


def path_time(model: TravelModel, start: FloatArray, targets: FloatArray) -> float:
    """Travel time (s) from ``start`` through ``targets`` (N, A) in the given order."""
    if len(targets) == 0:
        return 0.0
    previous = np.vstack([np.asarray(start, dtype=np.float64)[None, :], targets[:-1]])
    return float(model.time(previous, targets).sum())


def _scaled(model: TravelModel, points: FloatArray, t: float) -> FloatArray:
    """Coordinates where the Chebyshev distance ≤ 1 is exactly a move of ≤ t seconds."""
    return np.asarray(points / np.maximum(model.reach(t), 1e-300), dtype=np.float64)


def _typical_move(model: TravelModel, points: FloatArray) -> float:
    """The median nearest-neighbour move time (s), for scaling the proxy metric."""
    tree = cKDTree(points / model.velocity)
    k = min(2, len(points))
    _, idx = tree.query(points / model.velocity, k=k, p=np.inf)
    idx = np.asarray(idx).reshape(len(points), k)
    t = model.time(points, points[idx[:, -1]])
    positive = t[t > 0]
    return float(np.median(positive)) if positive.size else 1.0


def neighbour_lists(model: TravelModel, points: FloatArray, k: int) -> np.ndarray:
    """(N, k') indices of each point's nearest others by travel time, nearest first,
    equal times in index order (candidates from a k-d tree in a proxy metric, ranked by
    the exact time)."""
    n = len(points)
    k = min(k, n - 1)
    if k <= 0:
        return np.zeros((n, 0), dtype=np.int64)
    scaled = _scaled(model, points, _typical_move(model, points))
    tree = cKDTree(scaled)
    _, idx = tree.query(scaled, k=min(2 * k + 1, n), p=np.inf)
    idx = np.asarray(idx, dtype=np.int64)
    t = model.time(points[:, None, :], points[idx])
    t[idx == np.arange(n)[:, None]] = np.inf  # not itself
    # Nearest first, equal times in index order (whatever order the tree returned them).
    by_index = np.argsort(idx, axis=1, kind="stable")
    rank = np.take_along_axis(
        by_index, np.argsort(np.take_along_axis(t, by_index, axis=1), axis=1, kind="stable"), 1
    )[:, :k]
    return np.asarray(np.take_along_axis(idx, rank, axis=1), dtype=np.int64)


def mst_lower_bound(model: TravelModel, points: FloatArray) -> tuple[float, bool]:
    """(weight of the minimum spanning tree over ``points`` (N, A) in travel time, exact).

    Kruskal in stages of growing threshold T: after a stage every move ≤ T has been
    considered, so the forest is part of the MST. The next stage (T × 1.5) needs only
    the moves between different components, and every such move has an end outside the
    largest component: those points are the only ones queried, so the late stages,
    where one component holds nearly everything, stay cheap. The k-d tree's box query in
    `_scaled` coordinates is exactly "moves ≤ T". If the first stage's pairs would not
    fit in memory, it starts at a quarter of T, and so on. If a later stage's would not,
    the bound so far is returned: every remaining MST edge joins two components and is
    longer than the last threshold T' fully considered, so w(forest) + (components − 1)·T'
    is still a lower bound on any path (exact = False).
    """
    n = len(points)
    if n <= 1:
        return 0.0, True
    threshold = _typical_move(model, points)
    labels = np.arange(n)  # component of each point
    components, weight = n, 0.0
    first = True
    while True:
        scaled = _scaled(model, points, threshold)
        tree = cKDTree(scaled)
        radius = 1.0 + 1e-12
        if first:
            if tree.count_neighbors(tree, radius, p=np.inf) > 2 * MAX_PAIRS + n:
                # Nothing is settled yet: start lower (at a small enough threshold only
                # the points themselves are within reach).
                threshold /= 4.0
                if threshold < 1e-12:  # millions of coincident poses: no useful bound
                    return 0.0, False
                continue
            pairs = tree.query_pairs(radius, p=np.inf, output_type="ndarray")
            u, v = pairs[:, 0], pairs[:, 1]
        else:
            largest = np.argmax(np.bincount(labels))
            active = np.flatnonzero(labels != largest)
            lengths = tree.query_ball_point(scaled[active], radius, p=np.inf, return_length=True)
            if lengths.sum() > MAX_PAIRS:
                return weight + (components - 1) * threshold / 1.5, False
            found = tree.query_ball_point(scaled[active], radius, p=np.inf)
            u = np.repeat(active, lengths)
            v = np.fromiter((j for row in found for j in row), np.int64, int(lengths.sum()))
        t = model.time(points[u], points[v])
        keep = (t <= threshold) & (labels[u] != labels[v])
        cu, cv, t = labels[u[keep]], labels[v[keep]], t[keep]
        # One edge per pair of components, the shortest (coo → csr would sum repeats).
        by_time = np.argsort(t, kind="stable")
        lo, hi = np.minimum(cu, cv)[by_time], np.maximum(cu, cv)[by_time]
        _, once = np.unique(lo * n + hi, return_index=True)
        lo, hi, t = lo[once], hi[once], t[by_time][once]
        graph = coo_matrix((t + TINY, (lo, hi)), shape=(components, components)).tocsr()
        forest = minimum_spanning_tree(graph)
        weight += float(forest.sum()) - forest.nnz * TINY
        components, merged = connected_components(forest, directed=False)
        labels = merged[labels]
        if components == 1:
            return weight, True
        first = False
        threshold *= 1.5


def nearest_neighbour(model: TravelModel, points: FloatArray, start: FloatArray) -> np.ndarray:
    """Greedy order: from the start, to the nearest unvisited target by travel time among
    the few nearest in a proxy metric (a k-d tree, rebuilt as targets run out): nearly
    always the true nearest, and the local search mends the rest."""
    n = len(points)
    order = np.empty(n, dtype=np.int64)
    if n == 0:
        return order
    time_of = model.scalar()
    scale = model.reach(_typical_move(model, points))
    scale = np.maximum(scale, 1e-300)
    rows = points.tolist()
    visited = np.zeros(n, dtype=np.bool_)
    remaining = np.arange(n)
    tree = cKDTree(points / scale)
    here = np.asarray(start, dtype=np.float64)
    here_row = here.tolist()
    for step in range(n):
        if len(remaining) > 64 and (n - step) * 4 < len(remaining):  # mostly visited
            remaining = np.flatnonzero(~visited)
            tree = cKDTree(points[remaining] / scale)
        k = 8
        best, best_t = -1, math.inf
        while best < 0:
            k = min(k, len(remaining))
            _, found = tree.query(here / scale, k=k, p=np.inf)
            for j in np.atleast_1d(found).tolist():
                c = int(remaining[j])
                if not visited[c]:
                    t = time_of(here_row, rows[c])
                    if t < best_t:
                        best, best_t = c, t
            k *= 4
        order[step] = best
        visited[best] = True
        here, here_row = points[best], rows[best]
    return order


class _Path:
    """An open path with fixed ends: node S (the start) first, node E (a free end: every
    move into it costs nothing) last; targets 0..n-1 in between."""

    def __init__(
        self, model: TravelModel, points: FloatArray, start: FloatArray, order: np.ndarray
    ):
        n = len(points)
        self.n = n
        self.S, self.E = n, n + 1
        self.rows = [*points.tolist(), np.asarray(start, dtype=np.float64).tolist()]
        self.nodes = np.concatenate([[self.S], order, [self.E]]).astype(np.int64)
        self.pos = np.empty(n + 2, dtype=np.int64)
        self.pos[self.nodes] = np.arange(n + 2)
        time_of = model.scalar()
        rows, end = self.rows, self.E

        def cost(u: int, v: int) -> float:
            if u == end or v == end:
                return 0.0
            return time_of(rows[u], rows[v])

        self.cost = cost

    def reverse(self, lo: int, hi: int) -> None:
        """Reverse the nodes at positions lo..hi (inclusive)."""
        segment = self.nodes[lo : hi + 1][::-1].copy()
        self.nodes[lo : hi + 1] = segment
        self.pos[segment] = np.arange(lo, hi + 1)

    def move_segment(self, i: int, length: int, after: int, flip: bool) -> None:
        """Move the nodes at positions i..i+length-1 to follow the node now at position
        ``after`` (outside the segment), reversed if ``flip``."""
        nodes = self.nodes
        segment = nodes[i : i + length].copy()
        if flip:
            segment = segment[::-1]
        if after < i:  # the segment moves back: the nodes in between shift forward
            lo, hi = after + 1, i + length - 1
            between = nodes[after + 1 : i].copy()
            block = np.concatenate([segment, between])
        else:  # the segment moves forward
            lo, hi = i, after
            between = nodes[i + length : after + 1].copy()
            block = np.concatenate([between, segment])
        nodes[lo : hi + 1] = block
        self.pos[block] = np.arange(lo, hi + 1)


def _improve(
    path: _Path, neighbours: np.ndarray, max_moves: int, deadline: float
) -> tuple[int, Stop]:
    """2-opt and Or-opt moves from each node whose don't-look bit is clear, until none
    improves, ``max_moves`` have been applied or ``deadline`` (`time.perf_counter`) has
    passed. Returns (moves applied, why it stopped).

    Everything but the deadline is deterministic: the queue starts in target order,
    neighbours are visited nearest first (`neighbour_lists`), the first improving move
    found is applied. Each node visit costs a bounded number of cost evaluations and a
    move wakes at most 7 nodes, so ``max_moves`` bounds the work as well.
    """
    cost, pos, nodes = path.cost, path.pos, path.nodes
    S, E = path.S, path.E
    nbr = neighbours.tolist()
    queue = deque(range(path.n))
    queued = np.ones(path.n + 2, dtype=np.bool_)
    queued[[S, E]] = True  # the ends never enter the queue
    moves = 0

    def wake(*nodes_: int) -> None:
        for u in nodes_:
            if not queued[u]:
                queued[u] = True
                queue.append(u)

    def two_opt(a: int) -> bool:
        i = int(pos[a])
        # Successor side: drop (a, a+), (c, c+); add (a, c), (a+, c+).
        b = int(nodes[i + 1])
        d_ab = cost(a, b)
        for c in nbr[a]:
            g1 = d_ab - cost(a, c)
            if g1 <= EPSILON:
                break
            j = int(pos[c])
            if c == b:  # (c is never E: E is in no neighbour list)
                continue
            d = int(nodes[j + 1])
            if d == a:
                continue
            gain = g1 + cost(c, d) - cost(b, d)
            if gain > EPSILON:
                lo, hi = (i + 1, j) if j > i else (j + 1, i)
                path.reverse(lo, hi)
                wake(a, b, c, d)
                return True
        # Predecessor side: drop (a-, a), (c-, c); add (a, c), (a-, c-).
        b = int(nodes[i - 1])
        d_ab = cost(b, a)
        for c in nbr[a]:
            g1 = d_ab - cost(a, c)
            if g1 <= EPSILON:
                break
            j = int(pos[c])
            if c == b or j == 0:
                continue
            d = int(nodes[j - 1])
            if d == a:
                continue
            gain = g1 + cost(d, c) - cost(b, d)
            if gain > EPSILON:
                lo, hi = (i, j - 1) if j > i else (j, i - 1)
                path.reverse(lo, hi)
                wake(a, b, c, d)
                return True
        return False

    def or_opt(a: int) -> bool:
        i0 = int(pos[a])
        for length in (1, 2, 3):
            for i in (i0, i0 - length + 1):  # segments starting or ending at a
                if i < 1 or i + length > path.n + 1 or (length == 1 and i != i0):
                    continue
                segment = nodes[i : i + length].tolist()
                first, last = segment[0], segment[-1]
                p, q = int(nodes[i - 1]), int(nodes[i + length])
                removed = cost(p, first) + cost(last, q) - cost(p, q)
                if removed <= EPSILON:
                    continue
                for end in (first, last):
                    for c in nbr[end]:
                        g1 = removed - cost(end, c)
                        if g1 <= EPSILON:
                            break
                        j = int(pos[c])
                        if i <= j < i + length:
                            continue
                        # Insert between c and its successor, then its predecessor.
                        for x, y, at in (
                            (c, int(nodes[j + 1]) if j <= path.n else -1, j),
                            (int(nodes[j - 1]) if j >= 1 else -1, c, j - 1),
                        ):
                            if x < 0 or y < 0:  # S first and E last: never between
                                continue
                            if i <= pos[x] < i + length or i <= pos[y] < i + length:
                                continue
                            # `end` sits next to c; the other end goes to the other side.
                            head, tail = (end, first if end == last else last)
                            if x == c:
                                added = cost(x, head) + cost(tail, y) - cost(x, y)
                                flip = head != first
                            else:
                                added = cost(x, tail) + cost(head, y) - cost(x, y)
                                flip = tail != first
                            if removed - added > EPSILON:
                                path.move_segment(i, length, at, flip)
                                wake(p, q, x, y, *segment)
                                return True
        return False

    while queue:
        if moves >= max_moves:
            return moves, "move budget"
        if time.perf_counter() > deadline:
            return moves, "time cap"
        a = queue.popleft()
        queued[a] = False
        if two_opt(a) or or_opt(a):
            moves += 1
    return moves, "converged"


def order_targets(
    model: TravelModel,
    targets: FloatArray,
    start: FloatArray,
    *,
    method: Method = "auto",
    max_moves: int | None = None,
    time_budget_s: float = 120.0,
    lower_bound: bool = True,
) -> Ordering:
    """Order ``targets`` (N, A) joint angles (rad) for the shortest travel from ``start``.

    ``method``: "given" improves the order given (e.g. a serpentine), "nearest" starts
    from nearest neighbour, "auto" starts from whichever of the two is shorter. The
    improvement stops when no move improves, after ``max_moves`` improving moves
    (default `default_moves`), or, as a safety cap, ``time_budget_s`` seconds of wall
    time from the call (the construction, O(n log n), always runs to the end). Unless
    the cap binds (``stopped == "time cap"``) the result depends only on the inputs.
    With ``lower_bound`` the MST bound over the start and the targets is computed too.
    """
    targets = np.asarray(targets, dtype=np.float64)
    start = np.asarray(start, dtype=np.float64)
    n = len(targets)
    budget = default_moves(n) if max_moves is None else max_moves
    started = time.perf_counter()
    deadline = started + time_budget_s
    given_s = path_time(model, start, targets)
    if n == 0:
        return Ordering(np.zeros(0, np.int64), 0.0, 0.0, 0.0, 0.0, True, 0, True, max_moves=budget)
    order = np.arange(n)
    if method in ("nearest", "auto"):
        greedy = nearest_neighbour(model, targets, start)
        if method == "nearest" or path_time(model, start, targets[greedy]) < given_s:
            order = greedy
    constructed_s = path_time(model, start, targets[order])
    everything = np.vstack([targets, start[None, :]])  # node n is the start
    neighbours = neighbour_lists(model, everything, NEIGHBOURS)
    path = _Path(model, targets, start, order)
    moves, stopped = _improve(path, neighbours, budget, deadline)
    order = path.nodes[1:-1].copy()
    travel_s = path_time(model, start, targets[order])
    ordered = time.perf_counter()
    bound, exact = mst_lower_bound(model, everything) if lower_bound else (0.0, False)
    return Ordering(
        order, travel_s, constructed_s, given_s, bound, exact, moves, stopped == "converged",
        stopped=stopped, max_moves=budget,
        order_wall_s=ordered - started, bound_wall_s=time.perf_counter() - ordered,
    )  # fmt: skip
