"""Placing points in the coordinate box: grids, serpentine order, sequences, warps."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import qmc

from gonio.planner import sampling


@given(st.lists(st.integers(1, 6), min_size=1, max_size=4))
def test_serpentine_is_a_path_of_unit_steps(shape: list[int]) -> None:
    shape_t = tuple(shape)
    order = sampling.serpentine(shape_t)
    assert sorted(order.tolist()) == list(range(int(np.prod(shape_t))))
    cells = np.stack(np.unravel_index(order, shape_t), axis=-1)
    steps = np.abs(np.diff(cells, axis=0))
    assert np.all(steps.sum(axis=1) == 1)  # one step on one axis each time
    assert order[0] == 0


def test_grid_is_cell_centres_in_c_order() -> None:
    unit = sampling.grid((2, 3))
    expected = [
        [0.25, 1 / 6],
        [0.25, 0.5],
        [0.25, 5 / 6],
        [0.75, 1 / 6],
        [0.75, 0.5],
        [0.75, 5 / 6],
    ]
    np.testing.assert_allclose(unit, expected, rtol=0, atol=1e-15)


def test_stratified_grid_has_one_point_per_cell() -> None:
    shape = (5, 7, 3)
    unit = sampling.grid(shape, jitter=np.random.default_rng(0))
    cells = np.floor(unit * np.asarray(shape)).astype(int)
    assert np.array_equal(cells, np.floor(sampling.grid(shape) * np.asarray(shape)).astype(int))
    assert not np.allclose(unit, sampling.grid(shape))


@pytest.mark.parametrize("strategy", ["sobol", "halton", "random"])
def test_sequences_fill_the_unit_cube_reproducibly(strategy: str) -> None:
    a = sampling.Sequence(strategy, 3, seed=4).draw(4096)
    b = sampling.Sequence(strategy, 3, seed=4).draw(4096)
    c = sampling.Sequence(strategy, 3, seed=5).draw(4096)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.min() >= 0.0 and a.max() < 1.0
    # Uniform: the centred L2 discrepancy is small (quasi-random far below random).
    limit = 2e-4 if strategy != "random" else 5e-3
    assert qmc.discrepancy(a) < limit


def test_sobol_continues_its_sequence_across_draws() -> None:
    one = sampling.Sequence("sobol", 2, seed=1)
    two = sampling.Sequence("sobol", 2, seed=1)
    joined = np.vstack([one.draw(1024), one.draw(1024)])
    assert np.array_equal(joined, two.draw(2048))


def test_unknown_sequence_strategy() -> None:
    with pytest.raises(ValueError, match="not a sequence strategy"):
        sampling.Sequence("grid", 2, 0)


def test_to_box_scales_and_warps() -> None:
    unit = np.array([[0.0, 0.5, 0.25], [1.0, 0.25, 0.5]])
    bounds = np.array([[0.0, 1.0], [0.0, np.pi], [-1.0, 1.0]])
    box = sampling.to_box(unit, bounds, np.array([1.0, 2.0, 1.0]))
    np.testing.assert_allclose(box, [[0.0, np.pi / 4, -0.5], [1.0, np.pi / 16, 0.0]])


def test_warp_power_puts_more_points_near_the_lower_bound() -> None:
    unit = sampling.Sequence("sobol", 1, 0).draw(8192)
    warped = sampling.to_box(unit, np.array([[0.0, 1.0]]), np.array([2.0]))
    # u² < x  ⟺  u < √x: a quarter of the range holds half the points.
    assert np.mean(warped < 0.25) == pytest.approx(0.5, abs=0.01)


def test_grid_shape_for_rounds_up() -> None:
    assert sampling.grid_shape_for(9.2, 3) == (10, 10, 10)
    assert sampling.grid_shape_for(0.1, 2) == (1, 1)
