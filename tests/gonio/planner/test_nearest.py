"""Nearest poses by travel time through the compiled k-d tree: the nearest-neighbour order
and each node's nearest others are exactly what a search of every pair gives, equal
times in index order (repeated poses, an axis that never moves, poses on a lattice)."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.planner.nearest import nearest_neighbour, nearest_others
from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel


def brute_greedy(model: TravelModel, points: np.ndarray, start: np.ndarray) -> list[int]:
    """From the start, the nearest unvisited point each step (lowest index on ties)."""
    left = list(range(len(points)))
    here, order = start, []
    while left:
        t = model.time(here, points[left])
        best = left[int(np.argmin(t))]  # argmin: the first of equal times
        order.append(best)
        left.remove(best)
        here = points[best]
    return order


def cases(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    points = rng.uniform(-2.0, 2.0, (300, 4))
    points[:, 3] = 0.0  # the rotation stage of an isotropic plan: never moves
    points[250:] = points[rng.integers(0, 250, 50)]  # repeated poses: zero-time moves
    lattice = np.stack(np.meshgrid(*[np.arange(3.0)] * 3, indexing="ij"), -1).reshape(-1, 3)
    points[:27, :3] = lattice * 0.5  # equal times everywhere
    return points


@pytest.mark.parametrize("seed", [0, 1])
def test_nearest_neighbour_order_is_the_greedy_one(rig: Rig, seed: int) -> None:
    points = cases(seed)
    start = np.zeros(4)
    got = nearest_neighbour(rig.travel, points, start)
    assert got.tolist() == brute_greedy(rig.travel, points, start)


@pytest.mark.parametrize("k", [1, 6, 10])
def test_nearest_others_are_the_nearest_in_index_order(rig: Rig, k: int) -> None:
    points = cases(k)
    n = len(points)
    nodes, times = nearest_others(rig.travel, points, np.arange(n), k)
    every = rig.travel.time(points[:, None, :], points[None, :, :])
    every[np.arange(n), np.arange(n)] = np.inf
    best = np.lexsort((np.broadcast_to(np.arange(n), (n, n)), every), axis=1)[:, :k]
    np.testing.assert_array_equal(nodes, best)
    assert times.tobytes() == np.take_along_axis(every, best, axis=1).tobytes()


def test_tiny_inputs(rig: Rig) -> None:
    model = rig.travel
    assert nearest_neighbour(model, np.zeros((0, 4)), np.zeros(4)).shape == (0,)
    assert nearest_neighbour(model, np.ones((1, 4)), np.zeros(4)).tolist() == [0]
    nodes, times = nearest_others(model, np.ones((1, 4)), np.zeros(1, np.int64), 10)
    assert nodes.shape == (1, 0) and times.shape == (1, 0)
    nodes, _ = nearest_others(model, np.eye(4)[:3], np.arange(3), 10)
    assert nodes.shape == (3, 2) and np.all(nodes >= 0)
