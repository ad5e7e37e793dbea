"""Pairs and coordinates that broke earlier versions, and per-pair bounds near the horizon.

Each case here is a regression test for a failure found by review: kept by name so
that what it guards is clear.
"""

import numpy as np
import pytest

import gonio.params as params
from gonio.errors import DomainError
from gonio.params.cases import near_horizon, roundtrip_error
from studies.params import exact

NAMES = params.names()


def roundtrip(name: str, wi, wo) -> float:
    p = params.get(name)
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    a, b = p.inverse(p.forward(wi, wo))
    return float(np.max(roundtrip_error(wi, wo, a, b)))


@pytest.mark.parametrize("name", NAMES)
def test_opposite_directions_an_ulp_apart_in_length(name: str) -> None:
    """wo one ulp short of unit: Rusinkiewicz once returned coordinates `valid` refused."""
    p = params.get(name)
    c = p.forward([1.0, 0.0, 0.0], [-0.9999999999999999, 0.0, 0.0])
    assert p.valid(c)
    assert roundtrip(name, [1.0, 0.0, 0.0], [-0.9999999999999999, 0.0, 0.0]) < 4e-16


def test_rusinkiewicz_opposite_pairs_normalized_separately() -> None:
    """normalize(v) and normalize(−s v): h is pure rounding noise (once 2.7e-10 off)."""
    rng = np.random.default_rng(61)
    v = rng.normal(size=(200_000, 3))
    v[:, 2] = 0.0
    s = rng.uniform(0.5, 2.0, (200_000, 1))
    wi = v / np.linalg.norm(v, axis=1, keepdims=True)
    wo = -s * v
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    assert roundtrip("rusinkiewicz", wi, wo) < 2e-15


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("tiny", [1e-150, 1e-170, 1e-200, 5e-324])
def test_tangent_parts_that_underflow_when_squared(name: str, tiny: float) -> None:
    """‖h̄‖² underflowed while φh did not: Rusinkiewicz returned another pair (error 1.4)."""
    pairs = [
        ([1.0, 0.0, 0.0], [-1.0, tiny, 0.0]),
        ([-tiny, 0.6, 0.8], [0.0, -0.6, 0.8]),
        ([0.0, tiny, 1.0], [0.0, 0.0, 1.0]),
        ([tiny, tiny, 1.0], [-tiny, 2 * tiny, 1.0]),
    ]
    for wi, wo in pairs:
        assert roundtrip(name, wi, wo) < 1e-15, (wi, wo)
    # and the conventions hold: a tangent part whose norm underflows to 0 has azimuth 0
    c = params.get(name).forward([0.0, tiny, 1.0], [0.0, tiny, 1.0])
    assert c[1] == (0.0 if tiny * tiny == 0.0 else np.pi / 2)


def test_hybrid_coordinates_accepted_by_tolerance_come_back_unit() -> None:
    """Just outside the thin corner near retro-reflection on the horizon (‖k‖ ≈ 1e-7,
    ‖h̄‖ ≈ 1): accepted within the tolerance, and mapped to unit directions."""
    p = params.get("hybrid")
    c = [np.sqrt(1 - 1e-14), 0.0, 1e-7, 0.0]
    assert p.valid(c)
    a, b = p.inverse(c)
    np.testing.assert_allclose([np.linalg.norm(a), np.linalg.norm(b)], 1.0, atol=4e-16)
    assert a[2] >= 0.0
    assert b[2] >= 0.0


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    "coords",
    [[1e200, 0.0, 0.3, 0.0], [0.3, 0.0, -1e200, 0.0], [0.3, 1e300, 0.3, 0.0], [np.inf] * 4],
)
def test_huge_coordinates_are_invalid_without_overflow(name: str, coords: list) -> None:
    p = params.get(name)
    assert not p.valid(coords)
    with pytest.raises(DomainError):
        p.inverse(coords)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    ("wi", "wo", "what"),
    [
        ([np.nan, 0.0, 1.0], [0.0, 0.0, 1.0], "NaN"),
        ([0.0, 0.0, -1.0], [0.0, 0.0, 1.0], "below the horizon"),
        ([0.6, 0.0, 0.8 + 1e-9], [0.0, 0.0, 1.0], "not unit"),
        ([0.6, 0.0, 0.8], [0.0, 0.0, 0.5], "not unit"),
    ],
)
def test_forward_refuses_what_is_not_a_direction_pair(name: str, wi, wo, what: str) -> None:
    with pytest.raises(DomainError, match="not unit vectors in the closed upper hemisphere"):
        params.get(name).forward(wi, wo)


def test_forward_error_names_the_first_bad_pair() -> None:
    wi = np.tile([0.0, 0.0, 1.0], (5, 1))
    wi[3] = [0.0, 0.0, 1.1]
    with pytest.raises(DomainError) as err:
        params.get("hybrid").forward(wi, wi)
    assert "1 of 5 direction pairs" in str(err.value)
    assert "first at index (3,)" in str(err.value)


def test_hybrid_theta_k_is_half_pi_with_both_directions_on_the_horizon() -> None:
    """hz = a = 0 (θk undefined as 0/0): the convention θk = π/2 puts k in the tangent
    plane, so both directions are on the horizon."""
    c = np.array([[0.6, 0.3, 0.8, 0.3 + np.pi / 2], [0.0, 0.0, 1.0, 1.0]])
    a, b = params.get("hybrid").inverse(c)
    np.testing.assert_array_equal(a[:, 2], 0.0)
    np.testing.assert_array_equal(b[:, 2], 0.0)
    np.testing.assert_allclose(params.get("hybrid").forward(a, b)[:, [0, 2]], c[:, [0, 2]])


@pytest.mark.parametrize("name", NAMES)
def test_every_near_horizon_pair_within_ten_times_its_own_bound(name: str) -> None:
    """Pair by pair, not only worst case against worst case (measured worst 1.4 to 3.0)."""
    wi, wo = near_horizon(48, seed=62)
    p = params.get(name)
    a, b = p.inverse(p.forward(wi, wo))
    measured = roundtrip_error(wi, wo, a, b)
    bound = exact.roundtrip_bounds(name, wi, wo)
    assert np.all(measured <= 10.0 * bound), np.max(measured / bound)
