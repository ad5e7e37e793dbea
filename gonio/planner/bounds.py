"""Lower bounds on the travel time of any open path from the start through every target.

Both bounds hold for every order and, on the relaxed any-branch time
(`gonio.planner.poses.Relaxed`: node to node, the shortest move between any of their
usable solutions), for every choice of inverse-kinematics solutions as well.

- `mst_bound`: the minimum spanning tree (every open path is a spanning tree). Exact,
  found by Kruskal in stages of growing threshold over a k-d tree (`staged_mst`).
- `held_karp_bound`: the Held–Karp 1-tree bound. With a penalty πᵢ per node, edges cost
  c′ᵢⱼ = cᵢⱼ + πᵢ + πⱼ; the path plus a free end E (joined to the start S and to the last
  target at no cost) is a tour, so every path costs at least
  L(π) = w′(MST over targets and S) + π_S + minₓ πₓ − 2 Σ π,
  the cheapest "1-tree" with E's two edges (E–S, and E to the target of least π).
  Subgradient ascent (πᵢ += step × (degreeᵢ − 2), Polyak steps toward the ordered length)
  raises L over a sparse candidate graph (neighbour lists and the MST: cheap, but only an
  estimate there); the bound reported is L at the best π with the exact MST of the
  complete graph (`staged_mst` with penalties), and never less than the MST bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from gonio.planner.poses import Relaxed
from gonio.rig import TravelModel
from gonio.types import FloatArray

#: Pairs the staged Kruskal may hold in memory before it gives up on exactness.
MAX_PAIRS = 10_000_000
#: Bands of penalty the staged Kruskal queries separately.
BANDS = 8
#: Subgradient steps of the Held–Karp ascent.
ASCENT_STEPS = 150


@dataclass(frozen=True)
class Tree:
    """A spanning tree (or, when memory ran out, a forest) over m nodes: its weight in
    the (penalized) cost, whether it is the exact minimum, and its edges (E, 2)."""

    weight: float
    exact: bool
    edges: np.ndarray


def typical_move(model: TravelModel, points: FloatArray) -> float:
    """The median nearest-neighbour move time (s), for scaling proxy metrics."""
    tree = cKDTree(points / model.velocity)
    k = min(2, len(points))
    _, idx = tree.query(points / model.velocity, k=k, p=np.inf)
    idx = np.asarray(idx).reshape(len(points), k)
    t = model.time(points, points[idx[:, -1]])
    positive = t[t > 0]
    return float(np.median(positive)) if positive.size else 1.0


def _scaled(model: TravelModel, points: FloatArray, t: float) -> FloatArray:
    """Coordinates where the Chebyshev distance ≤ 1 is exactly a move of ≤ t seconds."""
    return np.asarray(points / np.maximum(model.reach(t), 1e-300), dtype=np.float64)


def staged_mst(
    model: TravelModel,
    poses: FloatArray,
    owner: np.ndarray | None = None,
    penalty: FloatArray | None = None,
) -> Tree:
    """The minimum spanning tree over nodes whose poses are ``poses`` (P, A), pose p
    belonging to node ``owner[p]`` (default: one node per pose); an edge costs the
    shortest move between the two nodes' poses plus ``penalty`` (per node, default 0)
    at both ends.

    Kruskal in stages of growing threshold T: after a stage every edge ≤ T has been
    considered, so the forest is part of the MST. Penalties are shifted to a least of 0
    (a spanning tree has m − 1 edges: the shift is added back exactly), so an edge ≤ T
    from node u is a move ≤ T − π_u, which a k-d tree's box query in `_scaled`
    coordinates (radius: the largest ratio of reaches over the axes) finds, and the
    exact time then filters. The next stage (T × 1.5) needs only edges between
    components, each with an end outside the largest one: only those poses are queried.
    If the first stage's pairs would not fit in memory it starts at a quarter of T, and
    so on; if a later one's would not, the forest so far is returned with
    w + (components − 1)·T′ (T′ the last threshold fully considered: every missing edge
    costs more), still a lower bound (exact = False).
    """
    n_poses = len(poses)
    owner = np.arange(n_poses) if owner is None else np.asarray(owner, dtype=np.int64)
    m = int(owner.max()) + 1 if n_poses else 0
    if m <= 1:
        return Tree(0.0, True, np.zeros((0, 2), dtype=np.int64))
    pi = np.zeros(m) if penalty is None else np.asarray(penalty, dtype=np.float64)
    least = float(pi.min())
    pi = pi - least
    restore = 2.0 * least * (m - 1)
    typical = typical_move(model, poses)
    threshold = typical
    labels = np.arange(m)  # component of each node
    components, weight = m, 0.0
    edges: list[np.ndarray] = [np.zeros((0, 2), dtype=np.int64)]
    # Poses in bands of their node's penalty: band b is queried with the radius
    # T − π_u − (its least π), so a pose of small π does not collect the many poses
    # whose penalty puts them out of reach.
    cuts = np.unique(np.quantile(pi, np.linspace(0.0, 1.0, BANDS + 1))[:-1])
    band = np.searchsorted(cuts, pi, side="right") - 1  # per node
    members = [np.flatnonzero(band[owner] == b) for b in range(len(cuts))]
    first = True
    while True:
        reach = np.maximum(model.reach(threshold), 1e-300)
        scaled = poses / reach
        trees = [cKDTree(scaled[m_b]) for m_b in members]
        if first:
            active = np.arange(n_poses)
        else:
            largest = np.argmax(np.bincount(labels))
            active = np.flatnonzero(labels[owner] != largest)
        queries = []
        for b, tree in enumerate(trees):
            left = threshold - pi[owner[active]] - cuts[b]
            mine = active[left >= 0.0]
            radius = np.max(model.reach(left[left >= 0.0][:, None]) / reach, axis=1)
            radius *= 1.0 + 1e-12
            lengths = tree.query_ball_point(scaled[mine], radius, p=np.inf, return_length=True)
            queries.append((tree, mine, radius, np.asarray(lengths, dtype=np.int64), b))
        total = sum(int(q[3].sum()) for q in queries)
        if first and total > 2 * MAX_PAIRS + n_poses:
            threshold /= 4.0  # nothing is settled yet: start lower
            if threshold < 1e-12 * typical:  # millions of coincident poses
                return Tree(0.0, False, np.zeros((0, 2), dtype=np.int64))
            continue
        if not first and total > MAX_PAIRS:
            previous = threshold / 1.5
            bound = weight + (components - 1) * previous + restore
            return Tree(bound, False, np.concatenate(edges))
        us, vs = [], []
        for tree, mine, radius, lengths, b in queries:
            found = tree.query_ball_point(scaled[mine], radius, p=np.inf)
            us.append(np.repeat(mine, lengths))
            local = np.fromiter((j for row in found for j in row), np.int64, int(lengths.sum()))
            vs.append(members[b][local])
        u, v = np.concatenate(us), np.concatenate(vs)
        nu, nv = owner[u], owner[v]
        t = model.time(poses[u], poses[v]) + pi[nu] + pi[nv]
        keep = (t <= threshold) & (labels[nu] != labels[nv])
        nu, nv, t = nu[keep], nv[keep], t[keep]
        # One edge per pair of components, the shortest (coo → csr would sum repeats);
        # csgraph drops explicit zeros, so weights are shifted to be positive (every
        # spanning forest of the same graph has as many edges: the shift is exact).
        by_time = np.argsort(t, kind="stable")
        nu, nv, t = nu[by_time], nv[by_time], t[by_time]
        cu, cv = labels[nu], labels[nv]  # int64: lo·m + hi exceeds 2³¹ past 46 340 nodes
        lo, hi = np.minimum(cu, cv), np.maximum(cu, cv)
        keys, once = np.unique(lo * m + hi, return_index=True)
        graph = coo_matrix(
            (t[once] + 1.0, (lo[once], hi[once])), shape=(components, components)
        ).tocsr()
        forest = minimum_spanning_tree(graph).tocoo()
        weight += float(forest.data.sum()) - forest.nnz * 1.0
        # The forest's edges, back to the nodes that made them.
        a, b = np.minimum(forest.row, forest.col), np.maximum(forest.row, forest.col)
        picked = once[np.searchsorted(keys, a.astype(np.int64) * m + b)]
        edges.append(np.stack([nu[picked], nv[picked]], axis=1).astype(np.int64))
        components, merged = connected_components(forest, directed=False)
        labels = merged[labels].astype(np.int64)  # csgraph's int32 would overflow lo·m
        if components == 1:
            return Tree(weight + restore, True, np.concatenate(edges))
        first = False
        threshold *= 1.5


def mst_bound(model: TravelModel, points: FloatArray) -> tuple[float, bool]:
    """(weight of the minimum spanning tree over ``points`` (N, A) in travel time, exact)."""
    tree = staged_mst(model, np.asarray(points, dtype=np.float64))
    return tree.weight, tree.exact


@dataclass(frozen=True)
class Bounds:
    """Lower bounds (s) on every open path from the start through the targets, with
    any choice of solutions: the MST and the Held–Karp 1-tree bound (≥ the MST)."""

    mst_s: float
    held_karp_s: float
    exact: bool  # False if memory forced a weaker MST somewhere (still bounds)
    steps: int  # subgradient steps taken


def _one_tree(
    u: np.ndarray, v: np.ndarray, c: FloatArray, pi: FloatArray, start: int
) -> tuple[float, np.ndarray]:
    """(L(π), node degrees in the 1-tree) over the candidate edges (u, v) of cost c."""
    m = len(pi)
    w = c + pi[u] + pi[v]
    shift = 1.0 - min(float(w.min()), 0.0)
    tree = minimum_spanning_tree(coo_matrix((w + shift, (u, v)), shape=(m, m)).tocsr()).tocoo()
    x = int(np.argmin(pi[:start]))  # E's second edge: the target of least π
    value = float(tree.data.sum()) - tree.nnz * shift + pi[start] + pi[x] - 2.0 * pi.sum()
    degree = np.bincount(np.concatenate([tree.row, tree.col]), minlength=m)
    degree[start] += 1
    degree[x] += 1
    return value, degree


def held_karp_bound(
    relaxed: Relaxed, upper: float, steps: int = ASCENT_STEPS, neighbours: int = 8
) -> Bounds:
    """The MST and Held–Karp bounds on the relaxed any-branch time of ``relaxed`` (so
    on every order with every choice of solutions); ``upper``: a path's length (s), for
    the ascent's steps; the ascent's sparse graph: each node's ``neighbours`` nearest."""
    flat, owner = relaxed.flat()
    if relaxed.n == 0:
        return Bounds(0.0, 0.0, True, 0)
    nbr, times = relaxed.neighbour_lists(neighbours)
    u = np.repeat(np.arange(len(nbr)), nbr.shape[1])
    v, t = nbr.reshape(-1), times.reshape(-1)
    keep = v >= 0
    u, v, t = np.minimum(u[keep], v[keep]), np.maximum(u[keep], v[keep]), t[keep]
    return _held_karp(relaxed.model, flat, owner, (u, v, t), upper, steps)


def _held_karp(
    model: TravelModel,
    poses: FloatArray,
    owner: np.ndarray,
    candidates: tuple[np.ndarray, np.ndarray, FloatArray],
    upper: float,
    steps: int = ASCENT_STEPS,
) -> Bounds:
    """The MST and Held–Karp bounds over nodes 0..m−1 whose usable poses are ``poses``
    (P, A) owned by ``owner`` (P,); node m − 1 is the start. ``candidates``: the sparse
    graph of the ascent, (u, v, cost) with u < v (the relaxed times of neighbour pairs);
    the MST's edges are added so that it is connected. ``upper``: a path's length (s),
    for the step sizes. Deterministic: the same inputs give the same bound.
    """
    mst = staged_mst(model, poses, owner)
    m = int(owner.max()) + 1
    start = m - 1
    if m <= 2:
        return Bounds(mst.weight, mst.weight, mst.exact, 0)
    u, v, c = candidates
    e = np.sort(mst.edges, axis=1)
    u = np.concatenate([u, e[:, 0]])
    v = np.concatenate([v, e[:, 1]])
    c = np.concatenate([c, _relaxed_times(model, poses, owner, e[:, 0], e[:, 1])])
    _, once = np.unique(u * m + v, return_index=True)
    u, v, c = u[once], v[once], c[once]
    pi = np.zeros(m)
    best, best_pi = -np.inf, pi.copy()
    scale, stale, taken = 2.0, 0, 0
    for taken in range(1, steps + 1):  # noqa: B007 - the count is reported
        value, degree = _one_tree(u, v, c, pi, start)
        g = (degree - 2).astype(np.float64)
        if value > best + 1e-12:
            best, best_pi, stale = value, pi.copy(), 0
        else:
            stale += 1
            if stale >= 10:
                scale, stale = scale / 2.0, 0
        norm = float(g @ g)
        if norm == 0.0 or upper <= value:  # a path itself, or the bound meets it
            break
        pi = pi + scale * (upper - value) / norm * g
    exact_tree = staged_mst(model, poses, owner, best_pi)
    x = int(np.argmin(best_pi[:start]))
    value = exact_tree.weight + best_pi[start] + best_pi[x] - 2.0 * float(best_pi.sum())
    return Bounds(mst.weight, float(max(value, mst.weight)), mst.exact and exact_tree.exact, taken)


def _relaxed_times(
    model: TravelModel, poses: FloatArray, owner: np.ndarray, a: np.ndarray, b: np.ndarray
) -> FloatArray:
    """The shortest move between any pose of node a and any of node b, pair by pair."""
    order = np.argsort(owner, kind="stable")
    first = np.searchsorted(owner[order], np.arange(int(owner.max()) + 2))
    best = np.full(len(a), np.inf)
    counts = np.diff(first)
    for i in range(int(counts.max())):
        for j in range(int(counts.max())):
            ok = (counts[a] > i) & (counts[b] > j)
            pa = poses[order[np.minimum(first[a] + i, len(order) - 1)]]
            pb = poses[order[np.minimum(first[b] + j, len(order) - 1)]]
            best = np.where(ok, np.minimum(best, model.time(pa, pb)), best)
    return best
