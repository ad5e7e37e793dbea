"""aperture_integral: convergence to the point value, a Lambertian cap in closed form,
a sharp GGX peak lowered and widened, horizon handling, shapes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.errors import DomainError
from gonio.radiometry import CollimatedSource, PointSource, aperture_integral, cap_half_angle
from tests.gonio.radiometry.helpers import GRAZING, NORMAL, direction, hemisphere

SHARP = brdf.create("cook_torrance", alpha=0.02, f0=0.9)


@pytest.mark.parametrize("weight", ["cos", "one"])
@pytest.mark.parametrize(
    "model",
    [brdf.create("cook_torrance", alpha=0.2, kd=0.1), SHARP, brdf.create("phong", n=50.0)],
    ids=["ggx_0.2", "ggx_0.02", "phong_50"],
)
def test_converges_to_the_point_value_as_the_aperture_shrinks(model, weight):
    wi, wo = direction(0.6, 0.0), direction(0.62, math.pi + 0.01)  # near the mirror
    point = model.eval(wi, wo) * (wo[2] if weight == "cos" else 1.0)
    errors = [
        abs(aperture_integral(model.eval, wi, wo, omega, weight) / omega / point - 1)
        for omega in (1e-3, 1e-4, 1e-5, 1e-6)
    ]
    assert all(a > 5 * b for a, b in itertools.pairwise(errors))  # ∝ Ω
    assert errors[-1] < 1e-3


@settings(max_examples=50)
@given(st.floats(1e-6, 2 * math.pi), st.floats(0.05, 1.0))
def test_lambertian_cap_around_the_normal(omega, albedo):
    """∫_cap cos θ dω = π sin²α around the normal: A = ρ sin²α; with weight 1, A = ρΩ/π."""
    model = brdf.create("lambert", albedo=albedo)
    alpha = cap_half_angle(omega)
    a_cos = aperture_integral(model.eval, NORMAL, NORMAL, omega, "cos")
    assert a_cos == pytest.approx(albedo * math.sin(alpha) ** 2, rel=1e-13)
    a_one = aperture_integral(model.eval, NORMAL, NORMAL, omega, "one")
    assert a_one == pytest.approx(albedo * omega / math.pi, rel=1e-13)


@settings(max_examples=50)
@given(st.floats(1e-6, 0.3), st.floats(0.0, 1.2), st.floats(0.0, 2 * math.pi))
def test_lambertian_cap_anywhere_above_the_horizon(omega, theta_o, phi_o):
    """∫_cap ω dω = π sin²α · wo, so ∫_cap cos θ dω = π sin²α cos θo while the cap stays
    above the horizon: a Lambertian value changes only through the cos weighting."""
    alpha = cap_half_angle(omega)
    theta_o = min(theta_o, math.pi / 2 - alpha - 1e-9)
    model = brdf.create("lambert", albedo=0.7)
    wo = direction(theta_o, phi_o)
    a = aperture_integral(model.eval, direction(0.3, 1.0), wo, omega, "cos")
    assert a == pytest.approx(0.7 * math.sin(alpha) ** 2 * math.cos(theta_o), rel=1e-12)


def test_sharp_ggx_peak_is_lowered_and_widened():
    wi = direction(math.radians(30), 0.0)
    mirror = direction(math.radians(30), math.pi)
    omega = 1e-3
    peak = SHARP.eval(wi, mirror)
    averaged = aperture_integral(SHARP.eval, wi, mirror, omega, "one") / omega
    assert averaged < 0.85 * peak  # measured 0.81
    # off the peak (3° and 5°) the averaged value exceeds the point value: a wider lobe
    for off in (3.0, 5.0):
        wo = direction(math.radians(30 + off), math.pi)
        point = SHARP.eval(wi, wo)
        assert aperture_integral(SHARP.eval, wi, wo, omega, "one") / omega > 1.02 * point


def test_default_order_against_a_refined_rule():
    """The default (12, 24) rule against (96, 192), GGX α = 0.02 at and around the mirror
    direction: ≤ 1e-12 at Ω = 1e-3 sr, ≤ 1e-5 at 1e-2 sr."""
    wi = direction(math.radians(30), 0.0)
    for off in (0.0, 1.0, 3.0, 6.0):
        wo = direction(math.radians(30 + off), math.pi + 0.05)
        for omega, tol in ((1e-3, 1e-12), (1e-2, 1e-5)):
            ref = aperture_integral(SHARP.eval, wi, wo, omega, "cos", order=(96, 192))
            assert aperture_integral(SHARP.eval, wi, wo, omega, "cos") == pytest.approx(
                ref, rel=tol
            )


def test_directions_below_the_horizon_contribute_nothing():
    """A cap centred on the horizon (wo grazing): only its upper half counts. Weight 1:
    ρΩ/(2π) for a Lambertian. Weight cos: (ρ/π) ∫ max(z, 0) dω = (ρ/π)(α − sin α cos α)."""
    model = brdf.create("lambert", albedo=0.5)
    for omega in (1e-3, 0.1, 2 * math.pi):
        a = aperture_integral(model.eval, NORMAL, GRAZING, omega, "one")
        assert a == pytest.approx(0.5 / math.pi * omega / 2, rel=1e-12)
        alpha = cap_half_angle(omega)
        a = aperture_integral(model.eval, NORMAL, GRAZING, omega, "cos")
        exact = 0.5 / math.pi * (alpha - math.sin(alpha) * math.cos(alpha))
        assert a == pytest.approx(exact, rel=2e-4)
        refined = aperture_integral(model.eval, NORMAL, GRAZING, omega, "cos", order=(64, 24))
        assert refined == pytest.approx(exact, rel=2e-6)
    # a cap partly below the horizon, wo at 89.5°: against a refined rule
    wo = direction(math.radians(89.5), 0.3)
    ref = aperture_integral(model.eval, NORMAL, wo, 1e-2, "cos", order=(96, 192))
    assert aperture_integral(model.eval, NORMAL, wo, 1e-2, "cos") == pytest.approx(ref, rel=1e-4)


def test_weight_from_a_source_and_shapes():
    rng = np.random.default_rng(8)
    wi, wo = hemisphere(rng, 6).reshape(2, 3, 3), hemisphere(rng, 3).reshape(1, 3, 3)
    model = brdf.create("cook_torrance", alpha=0.2, f0=(0.9, 0.6, 0.3))
    beam = aperture_integral(model.eval, wi, wo, 1e-3, CollimatedSource(1.0, 5.0))
    assert beam.shape == (2, 3, 3)
    np.testing.assert_array_equal(beam, aperture_integral(model.eval, wi, wo, 1e-3, "cos"))
    lamp = aperture_integral(model.eval, wi, wo, 1e-3, PointSource(1.0, 100.0))
    np.testing.assert_array_equal(lamp, aperture_integral(model.eval, wi, wo, 1e-3, "one"))
    single = aperture_integral(model.eval, wi[1, 2], wo[0, 2], 1e-3, "cos")
    np.testing.assert_allclose(beam[1, 2], single, rtol=1e-14)
    assert aperture_integral(SHARP.eval, NORMAL, NORMAL, 1e-3, "cos").shape == ()


def test_extremes_are_finite():
    for wi, wo in [(GRAZING, GRAZING), (NORMAL, NORMAL), (GRAZING, NORMAL), (NORMAL, GRAZING)]:
        for omega in (1e-9, 1e-3, 2 * math.pi):
            assert np.isfinite(aperture_integral(SHARP.eval, wi, wo, omega, "cos"))


def test_cap_half_angle():
    assert cap_half_angle(2 * math.pi) == pytest.approx(math.pi / 2, rel=1e-15)
    assert cap_half_angle(1e-12) == pytest.approx(math.sqrt(1e-12 / math.pi), rel=1e-9)
    alpha = cap_half_angle(0.01)
    assert 2 * math.pi * (1 - math.cos(alpha)) == pytest.approx(0.01, rel=1e-13)


@pytest.mark.parametrize(
    "call",
    [
        lambda: aperture_integral(SHARP.eval, NORMAL, NORMAL, 0.0, "cos"),
        lambda: aperture_integral(SHARP.eval, NORMAL, NORMAL, 7.0, "cos"),
        lambda: aperture_integral(SHARP.eval, NORMAL, NORMAL, 1e-3, "sin"),  # type: ignore[arg-type]
        lambda: aperture_integral(SHARP.eval, NORMAL, NORMAL, 1e-3, "cos", order=(4, 0)),
        lambda: aperture_integral(SHARP.eval, NORMAL, [0.0, 0.0, -1.0], 1e-3, "cos"),
    ],
)
def test_invalid_inputs_raise_one_line(call):
    with pytest.raises(DomainError) as err:
        call()
    assert "\n" not in str(err.value)
