"""The `lkh` ordering: an open path from the start through every target by LKH-3
(Helsgaun), through the optional `elkai` package (``pip install 'gonio[lkh]'``).

The path becomes a tour with one extra node, the free end E, that every node reaches at
no cost: S → … → last → E → S costs what the open path from S does. LKH reads integer
weights: move times are written in microseconds (rounded), so a tour it returns may be
up to n µs off its optimum in seconds; the caller times the order exactly. LKH's search
is seeded (its default SEED = 1), so the same poses give the same order. It needs the
full matrix in memory (as text): minutes and gigabytes beyond ~10 000 targets.
"""

from __future__ import annotations

import numpy as np

from gonio.planner.poses import choose
from gonio.planner.search import path_time
from gonio.rig import TravelModel
from gonio.types import BoolArray, FloatArray

#: Weights are written in this unit (s) and rounded to integers.
UNIT_S = 1e-6


def available() -> bool:
    """Whether `elkai` (LKH-3) is installed."""
    try:
        import elkai  # noqa: F401  # optional: the lkh extra
    except ImportError:
        return False
    return True


def _weights(model: TravelModel, targets: FloatArray, start: FloatArray) -> np.ndarray:
    """The full matrix of integer weights (µs): nodes 0..n-1 the targets, n the start S,
    n+1 the free end E (elkai writes it as TSPLIB's FULL_MATRIX, symmetric: a TSP).

    The tour must hold the edge S–E: every other edge at S costs M = the longest move
    + 1 more. A tour has two edges at S, so one without S–E pays 2M; taking S–E saves M
    and costs at most the longest move elsewhere (triangle inequality), so every optimal
    tour holds it and the constant M changes no comparison between tours that do.
    """
    poses = np.vstack([targets, start[None, :]])
    m = len(poses)
    weights = np.empty((m + 1, m + 1), dtype=np.int64)
    for i in range(m):
        weights[i, :m] = np.rint(model.time(poses[i], poses) / UNIT_S)
    weights[m, :], weights[:, m] = 0, 0  # E: the free end
    penalty = int(weights.max()) + 1
    weights[m - 1, : m - 1] += penalty
    weights[: m - 1, m - 1] += penalty
    return weights


def lkh_order(
    model: TravelModel, targets: FloatArray, start: FloatArray, *, runs: int = 1
) -> np.ndarray:
    """Indices of ``targets`` (N, A) in LKH-3's visiting order from ``start`` (A,).

    `ImportError` (with how to install it) without `elkai`.
    """
    try:
        import elkai  # optional: the lkh extra
    except ImportError as missing:  # pragma: no cover - depends on the environment
        raise ImportError("the lkh ordering needs elkai: pip install 'gonio[lkh]'") from missing
    targets = np.asarray(targets, dtype=np.float64)
    start = np.asarray(start, dtype=np.float64)
    n = len(targets)
    if n <= 2:  # too few for LKH: the better of the two orders
        orders = [np.arange(n), np.arange(n)[::-1]]
        times = [path_time(model, start, targets[o]) for o in orders]
        return np.asarray(orders[int(np.argmin(times))], dtype=np.int64)
    closed = elkai.DistanceMatrix(_weights(model, targets, start).tolist()).solve_tsp(runs=runs)
    tour = [int(i) for i in closed[:-1]]  # the tour, without its return to the first node
    s, e = n, n + 1
    k = tour.index(s)
    tour = tour[k:] + tour[:k]  # the start first
    if tour[1] == e:  # walked the other way: S, E, last, …, first
        tour = [s, *tour[1:][::-1]]
    assert tour[-1] == e
    return np.asarray(tour[1:-1], dtype=np.int64)


def improve(
    model: TravelModel,
    start: FloatArray,
    candidates: FloatArray,
    usable: BoolArray,
    order: np.ndarray,
    angles: FloatArray,
    travel: FloatArray,
) -> tuple[np.ndarray, FloatArray, FloatArray]:
    """LKH-3's order of the chosen poses ``angles`` (N, A) (the targets ``order`` of
    ``candidates`` (M, K, A), ``usable`` (M, K)), the solutions chosen again along it;
    kept if shorter than (order, angles, travel)."""
    again = order[lkh_order(model, angles, start)]
    lk_angles, lk_travel = choose(candidates[again], usable[again], start, model.time)
    if float(lk_travel.sum()) < float(travel.sum()):
        return again, lk_angles, lk_travel
    return order, angles, travel
