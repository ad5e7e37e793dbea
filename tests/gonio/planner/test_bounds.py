"""Lower bounds: the staged MST with several poses per node and with penalties equals
the dense one; the Held–Karp bound lies between the MST and the best path with the best
choice of solutions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import minimum_spanning_tree

from gonio.planner.bounds import held_karp_bound, staged_mst
from gonio.planner.poses import Relaxed, choose
from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel


def dense_mst(weights: np.ndarray) -> float:
    i, j = np.triu_indices(len(weights), 1)
    shift = 1.0 - min(weights[i, j].min(), 0.0)
    tree = minimum_spanning_tree(
        coo_matrix((weights[i, j] + shift, (i, j)), shape=weights.shape).tocsr()
    )
    return float(tree.sum()) - tree.nnz * shift


@pytest.mark.parametrize(("n", "per_node"), [(2, 1), (40, 1), (300, 3), (500, 2)])
def test_staged_mst_with_owners_and_penalties_is_the_dense_one(
    rig: Rig, n: int, per_node: int
) -> None:
    model = rig.travel
    rng = np.random.default_rng(n)
    poses = rng.uniform(-2.0, 2.0, (n, 4))
    owner = np.arange(n) // per_node
    m = int(owner.max()) + 1
    penalty = rng.uniform(-0.3, 0.3, m)
    t = model.time(poses[:, None, :], poses[None, :, :])
    weights = np.full((m, m), np.inf)
    np.minimum.at(weights, (owner[:, None], owner[None, :]), t)
    weights = weights + penalty[:, None] + penalty[None, :]
    tree = staged_mst(model, poses, owner, penalty)
    assert tree.exact and len(tree.edges) == m - 1
    assert tree.weight == pytest.approx(dense_mst(weights), rel=1e-12, abs=1e-12)


def best_any_branch(model: TravelModel, cand: np.ndarray, usable: np.ndarray) -> float:
    start = np.zeros(4)
    return min(
        float(choose(cand[list(p)], usable[list(p)], start, model.time)[1].sum())
        for p in itertools.permutations(range(len(cand)))
    )


@pytest.mark.parametrize("seed", range(4))
def test_held_karp_lies_between_the_mst_and_the_best_any_branch_path(rig: Rig, seed: int) -> None:
    model = rig.travel
    rng = np.random.default_rng(seed)
    cand = rng.uniform(-1.5, 1.5, (6, 2, 4))
    usable = rng.random((6, 2)) < 0.7
    usable[:, 0] = True
    relaxed = Relaxed.of(model, cand, usable, np.zeros(4))
    best = best_any_branch(model, cand, usable)
    b = held_karp_bound(relaxed, best)
    assert b.exact and b.steps > 0
    assert b.mst_s <= b.held_karp_s + 1e-12
    assert b.held_karp_s <= best + 1e-9
    assert b.held_karp_s > b.mst_s  # the ascent raised it


def test_held_karp_on_a_line_is_the_path(rig: Rig) -> None:
    """Targets on a line from the start: the path is a tree, both bounds are exact."""
    model = rig.travel
    line = np.linspace(0.1, 2.0, 30)[:, None] * np.array([1.0, 0.5, -0.3, 0.0])
    relaxed = Relaxed.of(model, line[:, None, :], np.ones((30, 1), bool), np.zeros(4))
    path = float(model.time(np.vstack([np.zeros(4), line[:-1]]), line).sum())
    b = held_karp_bound(relaxed, path)
    assert b.mst_s == pytest.approx(path) and b.held_karp_s == pytest.approx(path)
