"""The error metrics against hand-computed values, and the regions at known geometries."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from gonio.reconstruct.metrics import (
    METRICS,
    REGIONS,
    TRUTH_FLOOR,
    region_masks,
    relative_error,
    scores,
)
from tests.support.rigs import direction


def test_the_metrics_match_hand_computed_values() -> None:
    s = scores(np.array([1.0, 3.0]), np.array([1.0, 1.0]), np.array([1.0, 0.5]))
    assert s.count == 2
    assert s.log_rmse == pytest.approx(math.log(4 / 2) / math.sqrt(2), rel=1e-15)
    assert s.cos_log_rmse == pytest.approx(math.log(2.5 / 1.5) / math.sqrt(2), rel=1e-15)
    assert s.rel_rmse == pytest.approx(math.sqrt(2), rel=1e-15)  # e = 0, 2
    assert s.rel_median == pytest.approx(1.0)
    assert s.rel_p95 == pytest.approx(1.9)  # linear between the two order statistics


def test_a_perfect_candidate_scores_zero_everywhere() -> None:
    rng = np.random.default_rng(1)
    t = rng.uniform(0, 50, (1000, 3))
    s = scores(t.copy(), t, rng.uniform(0, 1, 1000))
    assert s.count == 1000
    assert all(getattr(s, m) == 0.0 for m in METRICS)


# Subnormal values are left out: an RMS below the smallest subnormal (5e-324) is 0 when
# correctly rounded. Normal ones as small as 1e-307 must still give a positive error
# (a plain sqrt(mean(d²)) underflowed for d = 2e-218).
values = hnp.arrays(
    np.float64, st.integers(1, 20), elements=st.floats(0.0, 1e4, allow_subnormal=False)
)


@given(values, st.floats(0.0, 1.0))
def test_log_metrics_are_symmetric_and_zero_only_for_equal_values(
    t: np.ndarray, cos: float
) -> None:
    c = t[::-1].copy()
    cosines = np.full(len(t), cos)
    forward, backward = scores(c, t, cosines), scores(t, c, cosines)
    assert forward.log_rmse == pytest.approx(backward.log_rmse, rel=1e-12, abs=1e-300)
    assert forward.cos_log_rmse == pytest.approx(backward.cos_log_rmse, rel=1e-12, abs=1e-300)
    assert (forward.log_rmse == 0.0) == np.array_equal(c, t)
    assert all(getattr(forward, m) >= 0.0 for m in METRICS)


def test_rgb_channels_pool_as_separate_values() -> None:
    rng = np.random.default_rng(2)
    c, t, cos = rng.uniform(0, 5, (50, 3)), rng.uniform(0, 5, (50, 3)), rng.uniform(0, 1, 50)
    pooled = scores(c.reshape(-1), t.reshape(-1), np.repeat(cos, 3))
    rgb = scores(c, t, cos)
    assert rgb.count == 50
    for m in METRICS:
        assert getattr(rgb, m) == pytest.approx(getattr(pooled, m), rel=1e-12)


def test_relative_error_divides_by_the_floor_below_it() -> None:
    e = relative_error(np.array([2e-4, 3.0, 0.0]), np.array([0.0, 2.0, 1e-6]))
    np.testing.assert_allclose(e, [2e-4 / TRUTH_FLOOR, 0.5, 1e-6 / TRUTH_FLOOR], rtol=1e-15)


def test_a_negative_candidate_counts_as_zero_in_the_log_metrics() -> None:
    s = scores(np.array([-5.0]), np.array([1.0]), np.array([1.0]))
    assert s.log_rmse == pytest.approx(math.log(2.0))
    assert s.rel_rmse == pytest.approx(6.0)


def test_no_pair_scores_none() -> None:
    s = scores(np.zeros(0), np.zeros(0), np.zeros(0))
    assert s.count == 0 and all(getattr(s, m) is None for m in METRICS)


def test_shapes_must_agree() -> None:
    with pytest.raises(ValueError, match="differ in shape"):
        scores(np.zeros((3, 3)), np.zeros(3), np.ones(3))


@pytest.mark.parametrize(
    ("wi", "wo", "region"),
    [
        ((30, 0), (30, 180), "mirror"),  # the mirror direction itself
        ((30, 0), (39, 180), "mirror"),  # 9° off it
        ((30, 0), (41, 180), "rest"),  # 11° off it
        ((30, 0), (30, 0), "retro"),
        ((30, 0), (30, 19), "retro"),  # 9.4° from ωi
        ((30, 0), (30, 21), "rest"),  # 10.4°
        ((3, 0), (3, 0), "mirror"),  # near the normal mirror and retro overlap: mirror wins
        ((75, 0), (75, 180), "grazing"),  # grazing wins over mirror
        ((10, 0), (71, 90), "grazing"),
        ((70, 0), (60, 90), "rest"),  # 70° is not above 70°
        ((0, 0), (45, 0), "rest"),
    ],
)
def test_regions_at_known_geometries(
    wi: tuple[float, float], wo: tuple[float, float], region: str
) -> None:
    masks = region_masks(direction(*wi)[None], direction(*wo)[None])
    assert [name for name in REGIONS if masks[name][0]] == [region]


def test_regions_are_disjoint_and_cover_every_pair() -> None:
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(2, 5000, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    masks = region_masks(wi, wo)
    assert list(masks) == list(REGIONS)
    total = sum(m.astype(int) for m in masks.values())
    assert np.all(total == 1)
    assert all(m.any() for m in masks.values())


def test_tiny_and_huge_differences_neither_underflow_nor_overflow() -> None:
    s = scores(np.array([2e-218, 0.0]), np.array([0.0, 0.0]), np.ones(2))
    assert s.log_rmse == pytest.approx(2e-218 / math.sqrt(2), rel=1e-15)
    s = scores(np.array([1e300, 0.0]), np.array([0.0, 1e300]), np.ones(2))
    assert s.rel_rmse is not None and math.isfinite(s.rel_rmse)
