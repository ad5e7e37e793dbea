"""The local search: a kick that does not pay is undone exactly, kicks never lengthen
the path, and the same seed gives the same path."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.planner import ordering, search
from gonio.planner.search import Path, path_time
from gonio.rig.travel import TravelModel

MODEL = TravelModel(np.array([1.0, 1.5, 2.0, 0.8]), np.array([4.0, 6.0, 3.0, 5.0]))


def setup(n: int, seed: int) -> tuple[np.ndarray, search.Neighbours, search.Cost]:
    points = np.random.default_rng(seed).uniform(-2.0, 2.0, (n, 4))
    everything = np.vstack([points, np.zeros((1, 4))])
    return (
        points,
        ordering._fixed_neighbours(MODEL, everything),
        ordering._fixed_cost(MODEL, points, np.zeros(4)),
    )


def test_undo_restores_the_path_exactly() -> None:
    _, neighbours, cost = setup(300, 0)
    path = Path(300, np.random.default_rng(1).permutation(300), cost)
    nodes, pos = path.nodes.copy(), path.pos.copy()
    path.journal = []
    path.reverse(3, 250)
    path.move_segment(10, 3, 200, True)
    path.move_segment(150, 2, 20, False)
    search.descend(path, neighbours, 50, float("inf"))
    assert not np.array_equal(path.nodes, nodes)
    path.undo()
    assert np.array_equal(path.nodes, nodes) and np.array_equal(path.pos, pos)


def test_kicks_never_lengthen_the_path_and_are_reproducible() -> None:
    points, neighbours, cost = setup(400, 2)
    lengths = []
    orders = []
    for _ in range(2):
        path = Path(400, np.arange(400), cost)
        search.descend(path, neighbours, 10**9, float("inf"))
        before = path.length()
        tried, kept, gained, stop = search.iterate(
            path, neighbours, 400, np.random.default_rng(7), float("inf")
        )
        after = path.length()
        assert tried == 400 and 0 < kept < 400 and stop == "move budget"
        assert after == pytest.approx(before - gained, abs=1e-9)
        assert after < before
        assert after == pytest.approx(path_time(MODEL, np.zeros(4), points[path.order()]))
        assert sorted(path.order().tolist()) == list(range(400))
        lengths.append(after)
        orders.append(path.order())
    assert lengths[0] == lengths[1] and np.array_equal(orders[0], orders[1])


def test_kicks_on_tiny_paths() -> None:
    for n in range(4):
        _, neighbours, cost = setup(n, n)
        path = Path(n, np.arange(n), cost)
        search.iterate(path, neighbours, 20, np.random.default_rng(0), float("inf"))
        assert sorted(path.order().tolist()) == list(range(n))
