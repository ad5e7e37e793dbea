"""The local search: its compiled move time is the rig's, bit for bit; a kick that does
not pay is undone exactly, kicks never lengthen the path, and the same seed gives the
same path."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.planner import ordering, search
from gonio.planner.search import Metric, Path, path_time
from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel

MODEL = TravelModel(np.array([1.0, 1.5, 2.0, 0.8]), np.array([4.0, 6.0, 3.0, 5.0]))


def setup(n: int, seed: int) -> tuple[np.ndarray, search.Neighbours, Metric]:
    points = np.random.default_rng(seed).uniform(-2.0, 2.0, (n, 4))
    everything = np.vstack([points, np.zeros((1, 4))])
    return points, ordering._fixed_neighbours(MODEL, everything), Metric.of(MODEL, everything)


@pytest.mark.parametrize("name", ["arch", "in_plane"])
def test_compiled_time_is_the_travel_model_bit_for_bit(rigs: dict[str, Rig], name: str) -> None:
    """Moves in every regime (axes short of the cruise speed, past it, still): the local
    search's time is `TravelModel.time`'s, to the last bit."""
    model = rigs[name].travel
    rng = np.random.default_rng(1)
    p = rng.uniform(-4, 4, (3000, 4))
    q = p + rng.uniform(-1, 1, (3000, 4)) * 10.0 ** rng.uniform(-9, 0.6, (3000, 4))
    q[::7, 2] = p[::7, 2]
    metric = Metric.of(model, np.vstack([p, q]))
    got = metric.times(np.arange(3000), np.arange(3000, 6000))
    assert got.tobytes() == model.time(p, q).tobytes()


def test_a_kick_that_does_not_pay_is_undone_exactly() -> None:
    """On a converged path no kick is kept: every one is undone, the path as it was."""
    _, neighbours, metric = setup(300, 0)
    path = Path(np.random.default_rng(1).permutation(300), metric)
    search.descend(path, neighbours, 10**9, float("inf"))
    for _ in range(3):  # kicks until none pays
        search.iterate(path, neighbours, 300, np.random.default_rng(5), float("inf"))
    nodes, pos = path.nodes.copy(), path.pos.copy()
    tried, kept, gained, _ = search.iterate(
        path, neighbours, 300, np.random.default_rng(5), float("inf")
    )
    assert tried == 300 and kept == 0 and gained == 0.0
    assert np.array_equal(path.nodes, nodes) and np.array_equal(path.pos, pos)


def test_kicks_never_lengthen_the_path_and_are_reproducible() -> None:
    points, neighbours, metric = setup(400, 2)
    lengths = []
    orders = []
    for _ in range(2):
        path = Path(np.arange(400), metric)
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
        assert np.array_equal(path.pos[path.nodes], np.arange(402))
        lengths.append(after)
        orders.append(path.order())
    assert lengths[0] == lengths[1] and np.array_equal(orders[0], orders[1])


def test_kicks_on_tiny_paths() -> None:
    for n in range(4):
        _, neighbours, metric = setup(n, n)
        path = Path(np.arange(n), metric)
        search.iterate(path, neighbours, 20, np.random.default_rng(0), float("inf"))
        assert sorted(path.order().tolist()) == list(range(n))
