"""spot_ratio: the point source's spot against the ideal chain, 1 in the limits,
symmetric, vectorized."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.radiometry import DetectorOptics, PointSource, spot_ratio
from tests.gonio.radiometry.helpers import direction, hemisphere

GGX = brdf.create("cook_torrance", alpha=0.2, f0=0.9)
S = 30.0  # sample diameter (mm)
#: View on the sample (F / cos θo ≤ S with F ≤ 25 mm): θo ≤ 33°.
VIEW = st.tuples(st.floats(0.0, 1.3), st.floats(0.0, 2 * np.pi))
LIGHT = st.tuples(st.floats(0.0, 1.3), st.floats(0.0, 2 * np.pi))


def ratio(distance, fov, wi, wo, model=None):
    return spot_ratio(PointSource(1.0, distance), DetectorOptics(1e-5, fov), S, wi, wo, model)


@settings(max_examples=40, deadline=None)
@given(LIGHT, st.floats(0.0, 0.57), st.floats(0.0, 2 * np.pi))
def test_tends_to_one_as_the_source_recedes_quadratically(light, theta_o, phi_o):
    wi, wo = direction(*light), direction(theta_o, phi_o)
    for model in (None, GGX.eval):
        near, far = (abs(ratio(r, 25.0, wi, wo, model) - 1.0) for r in (1e3, 1e4))
        assert far <= 0.011 * near + 1e-13  # (F/r)²: 100× smaller for 10× farther
        assert far < 1e-4


@settings(max_examples=40, deadline=None)
@given(LIGHT, st.floats(0.0, 0.57), st.floats(0.0, 2 * np.pi))
def test_tends_to_one_as_the_spot_shrinks(light, theta_o, phi_o):
    wi, wo = direction(*light), direction(theta_o, phi_o)
    for model in (None, GGX.eval):
        assert abs(ratio(300.0, 0.01, wi, wo, model) - 1.0) < 1e-8


@settings(max_examples=40, deadline=None)
@given(LIGHT, VIEW)
def test_symmetric_under_a_mirror_and_a_rotation_of_the_pair(light, view):
    wi, wo = direction(*light), direction(*view)
    base = ratio(300.0, 25.0, wi, wo, GGX.eval)
    mirror = np.array([1.0, -1.0, 1.0])
    assert np.isclose(ratio(300.0, 25.0, wi * mirror, wo * mirror, GGX.eval), base, rtol=1e-12)
    # the geometry alone does not see the pair's azimuth
    turned = ratio(300.0, 25.0, direction(light[0], light[1] + 1.0), direction(*view), None)
    alone = ratio(300.0, 25.0, wi, direction(view[0], view[1] - 1.0), None)
    assert np.isclose(turned, alone, rtol=1e-12)


def test_vectorized_over_pairs_and_a_constant_brdf_is_the_geometry():
    rng = np.random.default_rng(5)
    wi = hemisphere(rng, 40)
    wo = direction(rng.uniform(0.0, 0.57, 40), rng.uniform(0.0, 2 * np.pi, 40))
    batch = ratio(300.0, 25.0, wi, wo, GGX.eval)
    one = np.array([ratio(300.0, 25.0, a, b, GGX.eval) for a, b in zip(wi, wo, strict=True)])
    assert batch.shape == (40,) and batch.dtype == np.float64
    np.testing.assert_allclose(batch, one, rtol=1e-13)
    grid = ratio(300.0, 25.0, wi.reshape(8, 5, 3), wo.reshape(8, 5, 3), GGX.eval)
    np.testing.assert_allclose(grid.ravel(), batch, rtol=1e-13)
    lambert = brdf.create("lambert", albedo=0.5).eval
    np.testing.assert_allclose(ratio(300.0, 25.0, wi, wo, lambert), ratio(300.0, 25.0, wi, wo))


def test_the_lamps_fall_off_at_the_shipped_geometry():
    """A 25 mm view 300 mm from the lamp: the spot reads ~0.1 % off the ideal chain; on
    the normal, below it (the spot's edge is farther and more oblique)."""
    on_axis = float(ratio(300.0, 25.0, direction(0.0), direction(0.0)))
    assert -2e-3 < on_axis - 1.0 < -5e-4
