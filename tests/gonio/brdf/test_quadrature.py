"""The integrator the energy tests trust: exact cases and self-convergence on sharp lobes."""

from __future__ import annotations

import numpy as np
import pytest

import gonio.brdf as brdf
from gonio.brdf.quadrature import (
    default_n_phi,
    directional_albedo,
    hemisphere_integral,
    radial_rule,
)
from studies.brdf.examples import label


def test_radial_rule_integrates_polynomials_exactly():
    t, w = radial_rule(order=8, levels=10)
    assert np.all((t > 0) & (t < 1))
    for k in range(16):
        assert np.sum(w * t**k) == pytest.approx(1.0 / (k + 1), rel=1e-14)


def test_hemisphere_integral_of_known_functions():
    assert hemisphere_integral(lambda w: np.ones(w.shape[:-1])) == pytest.approx(2 * np.pi)
    assert hemisphere_integral(lambda w: w[..., 2]) == pytest.approx(np.pi, rel=1e-14)
    assert hemisphere_integral(lambda w: w[..., 0] ** 2) == pytest.approx(2 * np.pi / 3, rel=1e-14)
    # a sharp peak at the pole: ∫ (n + 1)/(2π) cos^n θ dω = 1
    n = 1e5
    value = hemisphere_integral(lambda w: (n + 1) / (2 * np.pi) * w[..., 2] ** n)
    assert value == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("theta_deg", [0.0, 45.0, 85.0, 89.0, 89.9])
def test_lambert_albedo_is_exact_to_near_grazing(theta_deg):
    a = directional_albedo(brdf.create("lambert", albedo=1.0), [np.radians(theta_deg)])
    assert a[0] == pytest.approx(1.0, abs=1e-12)


SHARP = [
    brdf.create("phong", n=1000),
    brdf.create("blinn_phong", n=1000),
    brdf.create("cook_torrance", alpha=0.05, fresnel="none"),
    brdf.create("cook_torrance", alpha=0.05, distribution="beckmann", fresnel="schlick"),
    brdf.create("ggx_anisotropic", alpha_x=0.05, alpha_y=0.3, fresnel="none"),
]


@pytest.mark.parametrize("model", SHARP, ids=label)
def test_albedo_self_convergence_on_sharp_lobes(model):
    theta = np.radians([0.0, 45.0, 85.0, 89.0])
    coarse = directional_albedo(model, theta)
    fine = np.array(
        [
            directional_albedo(model, [t], n_phi=2 * default_n_phi(t), order=24, levels=20)[0]
            for t in theta
        ]
    )
    np.testing.assert_allclose(coarse, fine, rtol=0.0, atol=1e-9)


def test_coarse_rules_do_not_resolve_a_sharp_lobe():
    # the test above can fail: too few nodes miss a GGX α = 0.05 peak by far more than 1e-9
    model = SHARP[2]
    good = directional_albedo(model, [0.3])[0]
    bad = directional_albedo(model, [0.3], n_phi=16, order=4, levels=3)[0]
    assert abs(bad - good) > 1e-4
