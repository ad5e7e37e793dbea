"""The isotropic reduction: invariances it promises and pairs it gives back."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import gonio.params as params
from gonio.params.cases import away
from tests.gonio.params.strategies import batch, pair

NAMES = params.names()
HALF = ["rusinkiewicz", "orthographic", "hybrid"]
pairs = st.lists(pair(), min_size=1, max_size=16).map(batch)


def rotate_z(w: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * w[..., 0] - s * w[..., 1], s * w[..., 0] + c * w[..., 1], w[..., 2]], -1)


def circular_gap(a: np.ndarray, b: np.ndarray, period: float) -> np.ndarray:
    d = np.mod(a - b, period)
    return np.minimum(d, period - d)


@pytest.mark.parametrize("name", NAMES)
def test_rotation_about_the_normal_is_rotated_out(name: str) -> None:
    p = params.get(name)
    wi, wo = away(5000, seed=51)
    base = p.forward_iso(wi, wo)
    period = p.iso_bounds[2, 1]
    for angle in (0.3, 2.0, -1.1):
        turned = p.forward_iso(rotate_z(wi, angle), rotate_z(wo, angle))
        np.testing.assert_allclose(turned[:, :2], base[:, :2], atol=1e-14)
        assert circular_gap(turned[:, 2], base[:, 2], period).max() < 1e-12


@pytest.mark.parametrize("name", HALF)
def test_reciprocity_fold_makes_swapped_pairs_equal(name: str) -> None:
    p = params.get(name)
    wi, wo = away(5000, seed=52)
    a, b = p.forward_iso(wi, wo), p.forward_iso(wo, wi)
    np.testing.assert_allclose(a[:, :2], b[:, :2], atol=1e-14)
    assert circular_gap(a[:, 2], b[:, 2], np.pi).max() < 1e-12
    assert np.all((a[:, 2] >= 0) & (a[:, 2] < np.pi))


def test_spherical_reduction_keeps_the_order_of_the_pair() -> None:
    p = params.get("spherical")
    wi, wo = away(100, seed=53)
    a, b = p.forward_iso(wi, wo), p.forward_iso(wo, wi)
    np.testing.assert_allclose(a[:, 0], b[:, 1], atol=1e-15)
    assert circular_gap(a[:, 2], -b[:, 2], 2 * np.pi).max() < 1e-12  # Δφ → −Δφ


@pytest.mark.parametrize("name", NAMES)
@given(pairs)
def test_inverse_iso_gives_an_equivalent_pair(name: str, ab: tuple) -> None:
    """The pair that comes back has the same elevations (up to the swap) and the same
    angle between its directions: it is the original rotated about n (and swapped)."""
    wi, wo = ab
    p = params.get(name)
    a, b = p.inverse_iso(p.forward_iso(wi, wo))
    np.testing.assert_allclose(
        np.sort(np.stack([a[:, 2], b[:, 2]], 1), 1),
        np.sort(np.stack([wi[:, 2], wo[:, 2]], 1), 1),
        atol=5e-8,
    )
    np.testing.assert_allclose(np.sum(a * b, 1), np.sum(wi * wo, 1), atol=5e-8)
    # The rotated-out azimuth is 0: φh = 0 (h̄ along +x) or φi = 0.
    lead = a if name == "spherical" else a + b
    assert np.all(np.abs(lead[:, 1]) <= 1e-12 + 1e-7 * np.abs(lead[:, 0]))
