"""Energy: directional albedo ≤ 1 for the physically based models, normalizations exact.

The albedo comes from `gonio.brdf.quadrature.directional_albedo` (halfway-domain
quadrature, peak at the pole; its accuracy is checked in test_quadrature.py:
< 1e-9 for the sharp lobes used here).
"""

from __future__ import annotations

import numpy as np
import pytest

import gonio.brdf as brdf
from gonio.brdf.models import blinn_normalization
from gonio.brdf.quadrature import directional_albedo
from studies.brdf.examples import blinn_overshoot, example_models, label

THETA_I = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 89.0])
TOL = 1e-9  # quadrature error bound (test_quadrature.py)

PHYSICAL = [m for m in example_models() if m.physically_based]


@pytest.mark.parametrize("model", PHYSICAL, ids=label)
def test_directional_albedo_at_most_one(model):
    a = directional_albedo(model, THETA_I)
    assert np.all(a >= 0.0)
    assert np.all(a <= 1.0 + TOL), a


@pytest.mark.parametrize("rho", [0.0, 0.3, 1.0])
def test_lambert_albedo_is_rho(rho):
    a = directional_albedo(brdf.create("lambert", albedo=rho), THETA_I)
    np.testing.assert_allclose(a, rho, rtol=0.0, atol=1e-12)


def test_lambert_rgb_albedo():
    a = directional_albedo(brdf.create("lambert", albedo=(0.1, 0.5, 0.9)), THETA_I[:3])
    np.testing.assert_allclose(a, np.tile([0.1, 0.5, 0.9], (3, 1)), atol=1e-12)


@pytest.mark.parametrize("n", [0.0, 0.5, 1.0, 8.0, 100.0, 1000.0])
@pytest.mark.parametrize("name", ["phong", "blinn_phong"])
def test_normalized_lobes_reach_exactly_one_at_normal_incidence(name, n):
    a = directional_albedo(brdf.create(name, n=n), np.radians([0.0, 1.0, 10.0, 45.0, 85.0]))
    assert a[0] == pytest.approx(1.0, abs=1e-9)
    assert np.all(np.diff(a) < 0.0) or n == 0.0  # and it is the maximum over θi


def test_phong_albedo_is_cos_theta_i_for_a_sharp_lobe_above_the_horizon():
    # ∫ cos^n ψ cos θo dωo over the whole cap = cos θi · 2π/(n + 2) (the cos θo
    # factor's tangential part integrates to 0); here the cap is all above the horizon
    # to within cos^1000 of 30°.
    theta = np.radians([10.0, 30.0, 50.0])
    a = directional_albedo(brdf.create("phong", n=1000), theta)
    np.testing.assert_allclose(a, np.cos(theta), rtol=1e-12)


def test_popular_blinn_normalization_overshoots():
    """(n + 8)/(8π) gives albedo > 1 at normal incidence for every n > 0 tested."""
    for n in (0.5, 1.0, 8.0, 100.0, 1000.0):
        model = brdf.create("blinn_phong", n=n)
        scale = (n + 8) / (8 * np.pi * float(blinn_normalization(n)))
        measured = scale * directional_albedo(model, [0.0])[0]
        assert measured == pytest.approx(blinn_overshoot(n), rel=1e-9)
        assert measured > 1.0
    assert blinn_overshoot(8.0) == pytest.approx(1.075, abs=1e-12)


def test_seed003_family_energy_is_not_held_to_one():
    # documented measurements: the cosine-quadratic lobes lose energy for large n,
    # Schlick's rational lobe has a heavy tail and gains it.
    at0 = {
        name: directional_albedo(brdf.create(name, n=100.0), [0.0])[0]
        for name in ("cosine_quadratic", "cosine_quadratic_modified", "schlick_lobe")
    }
    assert 0.6 < at0["cosine_quadratic"] < at0["cosine_quadratic_modified"] < 0.8
    assert at0["schlick_lobe"] > 2.0
    assert directional_albedo(brdf.create("cosine_quadratic_modified", n=2.0), [0.0])[0] > 1.0


def test_microfacet_albedo_approaches_one_for_a_smooth_surface():
    # α → 0 with F = 1: a mirror; single-scattering loss vanishes away from grazing.
    for dist in ("ggx", "beckmann"):
        model = brdf.create("cook_torrance", alpha=0.01, distribution=dist, fresnel="none")
        a = directional_albedo(model, np.radians([0.0, 45.0]))
        np.testing.assert_allclose(a, 1.0, atol=2e-3)


def test_conductor_albedo_channels_follow_their_normal_reflectance():
    gold = brdf.create(
        "cook_torrance",
        alpha=0.01,
        fresnel="conductor",
        ior=(0.18, 0.42, 1.37),
        k=(3.42, 2.35, 1.77),
    )
    a = directional_albedo(gold, [0.0])[0]
    n, k = np.array([0.18, 0.42, 1.37]), np.array([3.42, 2.35, 1.77])
    r0 = ((n - 1) ** 2 + k**2) / ((n + 1) ** 2 + k**2)
    np.testing.assert_allclose(a, r0, rtol=3e-3)
    assert a[0] > a[1] > a[2]  # gold reflects red best


def test_anisotropic_albedo_depends_on_the_azimuth_and_stays_below_one():
    model = brdf.create("ggx_anisotropic", alpha_x=0.05, alpha_y=0.5, fresnel="none")
    theta = np.radians([30.0, 80.0])
    along_x = directional_albedo(model, theta, phi_i=0.0, n_phi=1024)
    along_y = directional_albedo(model, theta, phi_i=np.pi / 2, n_phi=1024)
    diagonal = directional_albedo(model, theta, phi_i=np.pi / 4, n_phi=1024)
    for a in (along_x, along_y, diagonal):
        assert np.all(a <= 1.0 + TOL)
    assert abs(along_x[1] - along_y[1]) > 0.05  # measured: 0.789 (along x), 0.879 (along y)
    iso = brdf.create("ggx_anisotropic", alpha_x=0.2, alpha_y=0.2, fresnel="none")
    np.testing.assert_allclose(
        directional_albedo(iso, theta, phi_i=1.0), directional_albedo(iso, theta), atol=1e-12
    )
