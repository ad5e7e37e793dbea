"""Round trips over the whole closed domain (hypothesis), per parametrization and across them."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import gonio.params as params
from gonio.params.cases import away, roundtrip_error
from studies.params.accuracy import error_envelope
from tests.gonio.params.strategies import batch, pair

NAMES = params.names()
pairs = st.lists(pair(), min_size=1, max_size=16).map(batch)


@pytest.mark.parametrize("name", NAMES)
@given(pairs)
def test_round_trip_within_the_envelope_everywhere(name: str, ab: tuple) -> None:
    wi, wo = ab
    p = params.get(name)
    c = p.forward(wi, wo)
    assert np.all(np.isfinite(c)) and np.all(p.valid(c))
    a, b = p.inverse(c)
    assert np.all(a[:, 2] >= 0.0) and np.all(b[:, 2] >= 0.0)
    np.testing.assert_allclose(np.linalg.norm(a, axis=1), 1.0, atol=4e-16)
    np.testing.assert_allclose(np.linalg.norm(b, axis=1), 1.0, atol=4e-16)
    assert np.all(roundtrip_error(wi, wo, a, b) <= error_envelope(name, wi, wo))


@pytest.mark.parametrize("name", NAMES)
def test_round_trip_is_1e_12_away_from_the_extremes(name: str) -> None:
    wi, wo = away(200_000, seed=11)
    p = params.get(name)
    a, b = p.inverse(p.forward(wi, wo))
    worst = roundtrip_error(wi, wo, a, b).max()
    assert worst <= 1e-12
    # And far better than that: a few ulps (measured 0.8 to 1.6e-15).
    assert worst <= 4e-15


@pytest.mark.parametrize("first", NAMES)
@pytest.mark.parametrize("second", NAMES)
@given(pairs)
def test_between_every_pair_of_parametrizations(first: str, second: str, ab: tuple) -> None:
    """A → directions → B → directions stays within both envelopes."""
    wi, wo = ab
    pa, pb = params.get(first), params.get(second)
    a1, b1 = pa.inverse(pa.forward(wi, wo))
    a2, b2 = pb.inverse(pb.forward(a1, b1))
    envelope = error_envelope(first, wi, wo) + error_envelope(second, a1, b1)
    assert np.all(roundtrip_error(wi, wo, a2, b2) <= envelope)


@pytest.mark.parametrize("name", NAMES)
def test_coordinates_round_trip_away_from_the_extremes(name: str) -> None:
    """coordinates → directions → coordinates, azimuths compared on the circle."""
    p = params.get(name)
    c = p.forward(*away(50_000, seed=12))
    c2 = p.forward(*p.inverse(c))
    diff = np.abs(c2 - c)
    diff[:, [1, 3]] = np.minimum(diff[:, [1, 3]], 2 * np.pi - diff[:, [1, 3]])
    assert diff.max() <= 2e-14
