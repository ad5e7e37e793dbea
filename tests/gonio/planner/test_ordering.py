"""Ordering motor targets: the lower bound is the exact minimum spanning tree, the order
is a permutation whose path time is what it reports, local search leaves no improving
2-opt or Or-opt move, and on uniform targets it lands near the bound."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree

from gonio.planner import bounds, ordering
from gonio.planner.ordering import mst_lower_bound, order_targets, path_time
from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel


def dense_mst(model: TravelModel, points: np.ndarray) -> float:
    """The MST weight from the complete graph (every pair an explicit sparse entry, zero
    times nudged to stay edges)."""
    i, j = np.triu_indices(len(points), 1)
    t = model.time(points[i], points[j])
    graph = coo_matrix((t + 1e-300, (i, j)), shape=(len(points),) * 2).tocsr()
    return float(minimum_spanning_tree(graph).sum())


def poses(rng: np.random.Generator, n: int, model: TravelModel, spread: float = 2.0) -> np.ndarray:
    return rng.uniform(-spread, spread, (n, len(model.velocity)))


@pytest.mark.parametrize("n", [2, 3, 17, 300])
def test_mst_bound_is_the_exact_mst(rig: Rig, n: int) -> None:
    model = rig.travel
    points = poses(np.random.default_rng(n), n, model)
    bound, exact = mst_lower_bound(model, points)
    assert exact
    assert bound == pytest.approx(dense_mst(model, points), rel=1e-12)


@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 80),
    duplicates=st.integers(0, 10),
    frozen=st.booleans(),
)
def test_mst_bound_with_repeats_and_a_frozen_axis(
    rigs: dict[str, Rig], seed: int, n: int, duplicates: int, frozen: bool
) -> None:
    """Repeated poses (zero-time moves) and an axis that never moves (the rotation stage
    of an isotropic plan) change nothing: the staged Kruskal equals the dense MST."""
    model = rigs["arch"].travel
    rng = np.random.default_rng(seed)
    points = poses(rng, n, model, spread=rng.uniform(0.01, 3.0))
    points = np.vstack([points, points[rng.integers(0, n, duplicates)]])
    if frozen:
        points[:, 3] = 0.0
    bound, exact = mst_lower_bound(model, points)
    assert exact
    assert bound == pytest.approx(dense_mst(model, points), rel=1e-12, abs=1e-12)


def test_mst_bound_stays_a_bound_when_memory_runs_out(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    model = rigs["in_plane"].travel
    points = poses(np.random.default_rng(5), 400, model)
    exact_bound, _ = mst_lower_bound(model, points)
    monkeypatch.setattr(bounds, "MAX_PAIRS", 50)
    weak, exact = mst_lower_bound(model, points)
    assert not exact
    assert 0.0 < weak <= exact_bound


@pytest.mark.parametrize("limit", [0, 10, 300])
def test_weak_bound_never_exceeds_the_mst(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch, limit: int
) -> None:
    """Points on a line plus tight clusters (the typical move is tiny, most moves are
    long): however little memory the stages get, the bound stays below the MST."""
    model = rigs["arch"].travel
    rng = np.random.default_rng(8)
    line = np.linspace(0.0, 3.0, 201)[:, None] * np.array([1.0, 0.0, 0.0, 0.0])
    centres = rng.uniform(-2, 2, (20, 4))
    clusters = (centres[:, None, :] + rng.normal(0, 1e-4, (20, 10, 4))).reshape(-1, 4)
    points = np.vstack([line, clusters])
    exact, is_exact = mst_lower_bound(model, points)
    assert is_exact
    monkeypatch.setattr(bounds, "MAX_PAIRS", limit)
    weak, flag = mst_lower_bound(model, points)
    assert not flag
    assert 0.0 <= weak <= exact


@pytest.mark.parametrize("method", ["given", "nearest", "auto"])
def test_order_is_a_permutation_timed_as_reported(rig: Rig, method: str) -> None:
    model = rig.travel
    rng = np.random.default_rng(1)
    targets = poses(rng, 700, model)
    start = np.zeros(4)
    result = order_targets(model, targets, start, method=method, time_budget_s=30.0)
    assert sorted(result.order.tolist()) == list(range(len(targets)))
    assert result.travel_s == pytest.approx(path_time(model, start, targets[result.order]))
    assert result.given_s == pytest.approx(path_time(model, start, targets))
    assert result.converged
    # Improvement never makes the constructed order worse; the bound is a bound.
    assert result.lower_bound_s <= result.travel_s <= result.constructed_s + 1e-9
    if method == "given":
        assert result.constructed_s == pytest.approx(result.given_s)


def brute_force_best(model: TravelModel, start: np.ndarray, targets: np.ndarray) -> float:
    return min(
        path_time(model, start, targets[list(p)])
        for p in itertools.permutations(range(len(targets)))
    )


@pytest.mark.parametrize("seed", range(6))
def test_small_instances_near_the_optimum(rigs: dict[str, Rig], seed: int) -> None:
    """Seven targets: the search ends within 10 % of the brute-force optimum (2-opt and
    Or-opt optima are not always global) and never below it."""
    model = rigs["arch"].travel
    rng = np.random.default_rng(seed)
    targets = poses(rng, 7, model)
    start = np.zeros(4)
    best = brute_force_best(model, start, targets)
    result = order_targets(model, targets, start, method="given")
    assert best - 1e-9 <= result.travel_s <= 1.1 * best


def test_no_improving_two_opt_move_is_left(rigs: dict[str, Rig]) -> None:
    """With neighbour lists covering every target, the final path is 2-opt optimal."""
    model = rigs["in_plane"].travel
    rng = np.random.default_rng(3)
    targets = poses(rng, ordering.NEIGHBOURS, model)
    start = np.zeros(4)
    result = order_targets(model, targets, start, method="given")
    path = [start, *targets[result.order]]
    n = len(path)
    cost = model.time
    for i in range(n - 1):
        for j in range(i + 2, n):
            # Reverse path[i+1..j]: edges (i, i+1), (j, j+1) become (i, j), (i+1, j+1).
            before = float(cost(path[i], path[i + 1]))
            after = float(cost(path[i], path[j]))
            if j + 1 < n:
                before += float(cost(path[j], path[j + 1]))
                after += float(cost(path[i + 1], path[j + 1]))
            assert after >= before - 1e-9


def test_sorted_line_is_kept(rigs: dict[str, Rig]) -> None:
    """Targets on a line, given in order from the start: already optimal, unchanged."""
    model = rigs["arch"].travel
    targets = np.linspace(0.1, 2.0, 50)[:, None] * np.array([1.0, 0.5, -0.3, 0.0])
    result = order_targets(model, targets, np.zeros(4), method="given")
    assert result.order.tolist() == list(range(50))
    assert result.moves == 0
    assert result.travel_s == pytest.approx(result.lower_bound_s)


def test_shuffled_line_is_recovered(rigs: dict[str, Rig]) -> None:
    model = rigs["arch"].travel
    targets = np.linspace(0.1, 2.0, 200)[:, None] * np.array([1.0, 0.5, -0.3, 0.0])
    shuffled = np.random.default_rng(0).permutation(200)
    result = order_targets(model, targets[shuffled], np.zeros(4), method="auto")
    assert result.travel_s == pytest.approx(result.lower_bound_s, rel=1e-9)
    assert result.given_s > 5 * result.travel_s


def test_uniform_targets_near_the_bound_and_far_below_generation_order(rig: Rig) -> None:
    model = rig.travel
    targets = poses(np.random.default_rng(11), 1500, model, spread=1.4)
    result = order_targets(model, targets, np.zeros(4), time_budget_s=60.0)
    assert result.travel_s <= 1.3 * result.lower_bound_s
    assert result.given_s >= 2.0 * result.travel_s


def test_exhausted_budget_still_returns_a_valid_order(rigs: dict[str, Rig]) -> None:
    model = rigs["arch"].travel
    targets = poses(np.random.default_rng(2), 2000, model)
    result = order_targets(model, targets, np.zeros(4), method="given", time_budget_s=0.0)
    assert not result.converged
    assert sorted(result.order.tolist()) == list(range(2000))
    assert result.travel_s == pytest.approx(path_time(model, np.zeros(4), targets[result.order]))


@pytest.mark.parametrize("n", [0, 1])
def test_trivial_sizes(rigs: dict[str, Rig], n: int) -> None:
    model = rigs["arch"].travel
    targets = np.full((n, 4), 0.5)
    result = order_targets(model, targets, np.zeros(4))
    assert result.order.tolist() == list(range(n))
    expected = 0.0 if n == 0 else float(model.time(np.zeros(4), targets[0]))
    assert result.travel_s == pytest.approx(expected)
    assert result.lower_bound_s == pytest.approx(expected)
    assert math.isfinite(result.travel_s)


def test_start_pose_counts_in_the_bound(rigs: dict[str, Rig]) -> None:
    """The bound spans the start: one target far from the start costs its move."""
    model = rigs["arch"].travel
    target = np.array([[1.0, 0.0, 0.0, 0.0]])
    result = order_targets(model, target, np.zeros(4))
    assert result.lower_bound_s == pytest.approx(float(model.time(np.zeros(4), target[0])))


# --- a budget of moves, not of time: the same order on any machine ------------------


def test_the_same_inputs_give_the_same_order(rigs: dict[str, Rig]) -> None:
    model = rigs["in_plane"].travel
    targets = poses(np.random.default_rng(4), 1500, model)
    a = order_targets(model, targets, np.zeros(4), lower_bound=False)
    b = order_targets(model, targets, np.zeros(4), lower_bound=False)
    assert a.converged and a.stopped == "converged"
    assert np.array_equal(a.order, b.order)
    assert a.moves == b.moves and a.travel_s == b.travel_s
    assert a.max_moves == ordering.default_moves(1500)


@pytest.mark.parametrize("max_moves", [0, 1, 37, 400])
def test_the_move_budget_binds_before_any_time_cap(rigs: dict[str, Rig], max_moves: int) -> None:
    """With the move budget binding, a huge time cap and an ordinary one give the same
    order: the result does not depend on how fast the machine is."""
    model = rigs["arch"].travel
    targets = poses(np.random.default_rng(9), 1200, model)
    runs = [
        order_targets(
            model,
            targets,
            np.zeros(4),
            method="given",
            max_moves=max_moves,
            time_budget_s=cap,
            lower_bound=False,
        )
        for cap in (1e9, 20.0)
    ]
    for r in runs:
        assert r.moves == max_moves
        assert not r.converged and r.stopped == "move budget"
    assert np.array_equal(runs[0].order, runs[1].order)
    assert runs[0].travel_s == runs[1].travel_s
    # Each move improves: more moves, a shorter path.
    if max_moves:
        assert runs[0].travel_s < runs[0].given_s


def test_the_time_cap_is_reported_as_such(rigs: dict[str, Rig]) -> None:
    model = rigs["arch"].travel
    targets = poses(np.random.default_rng(2), 2000, model)
    result = order_targets(model, targets, np.zeros(4), method="given", time_budget_s=1e-9)
    assert result.stopped == "time cap" and not result.converged


def test_neighbour_ties_are_taken_in_index_order(rigs: dict[str, Rig]) -> None:
    """Equal move times rank by index, whatever order the k-d tree returns them in."""
    model = rigs["arch"].travel
    ring = np.array(
        [[1.0, 0, 0, 0], [-1.0, 0, 0, 0], [0, 0, 0, 0], [0, 1.0, 0, 0], [0, -1.0, 0, 0]]
    )
    for perm in ([0, 1, 2, 3, 4], [4, 3, 2, 1, 0], [1, 3, 2, 0, 4]):
        points = ring[perm]
        centre = perm.index(2)
        nbrs = ordering.neighbour_lists(model, points, 4)[centre].tolist()
        t = model.time(points[centre], points[nbrs])
        assert np.all(np.diff(t) >= 0)
        for i in range(len(nbrs) - 1):
            if t[i] == t[i + 1]:
                assert nbrs[i] < nbrs[i + 1]
