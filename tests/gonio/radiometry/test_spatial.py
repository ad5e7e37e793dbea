"""point_source_power: the disc's solid angle for a Lambertian sample under a source on
the normal, convergence to the ideal chain, the seen area clipped by the sample."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.errors import DomainError
from gonio.radiometry import (
    CollimatedSource,
    DetectorOptics,
    PointSource,
    footprint_fraction,
    point_source_power,
    radiant_power,
)
from tests.gonio.radiometry.helpers import GRAZING, NORMAL, direction, hemisphere

LAMBERT = brdf.create("lambert", albedo=0.8)


def _disc_solid_angle(h, radius):
    """2π(1 − h/√(h² + R²)), written without cancellation for h ≫ R."""
    return 2 * math.pi * radius**2 / (math.hypot(h, radius) * (math.hypot(h, radius) + h))


@settings(max_examples=50)
@given(
    st.floats(1e-2, 1e2),  # I (W/sr)
    st.floats(10.0, 1e4),  # h (mm)
    st.floats(2.0, 40.0),  # R (mm)
    st.floats(1e-5, 1e-1),  # Ω (sr)
)
def test_lambertian_on_axis_is_the_discs_solid_angle(intensity, h, radius, aperture):
    """Φ = Ω (ρ/π) I · 2π(1 − h/√(h² + R²)) with the detector along the normal and a field
    of view covering the whole sample, for h ≥ R/4 (the quadrature's accuracy is
    ≤ 2e-12 for h ≥ 0.6 R, 2e-7 at h = R/4; see docs/explanations/radiometry.md)."""
    h = max(h, radius / 4)
    source, optics = PointSource(intensity, h), DetectorOptics(aperture, 2.5 * radius)
    phi = point_source_power(source, optics, 2 * radius, LAMBERT.eval, NORMAL, NORMAL)
    expected = aperture * 0.8 / math.pi * intensity * _disc_solid_angle(h, radius)
    assert phi == pytest.approx(expected, rel=1e-6)


def test_on_axis_accuracy_by_height():
    optics = DetectorOptics(1e-3, 40.0)
    for h, tol in [(500.0, 1e-13), (50.0, 1e-13), (10.0, 1e-11), (3.75, 1e-6)]:
        phi = point_source_power(PointSource(1.0, h), optics, 30.0, LAMBERT.eval, NORMAL, NORMAL)
        expected = 1e-3 * 0.8 / math.pi * _disc_solid_angle(h, 15.0)
        assert phi == pytest.approx(expected, rel=tol)


@pytest.mark.parametrize(
    "model",
    [LAMBERT, brdf.create("cook_torrance", alpha=0.3, kd=0.1)],
    ids=["lambert", "ggx_0.3"],
)
def test_converges_to_the_ideal_chain_as_the_source_recedes(model):
    """With the seen ellipse on the sample (F/cos θo ≤ S) the only differences from the
    ideal chain are the spread of incidence and of 1/d² across the spot: O((F/r)²)."""
    wi, wo = direction(0.5, 0.2), direction(0.4, 2.9)
    optics = DetectorOptics(1e-3, 10.0)
    errors = []
    for r in (100.0, 1000.0, 10000.0):
        source = PointSource(1.0, r)
        phi = point_source_power(source, optics, 30.0, model.eval, wi, wo)
        ideal = radiant_power(source, optics, model.eval(wi, wo), wi, wo)
        errors.append(abs(phi / ideal - 1))
    assert errors[0] > errors[1] > errors[2]
    assert errors[1] / errors[2] > 50  # quadratic in 1/r
    assert errors[2] < 1e-5


def test_converges_to_the_ideal_chain_as_the_field_of_view_shrinks():
    model = brdf.create("cook_torrance", alpha=0.3, kd=0.1)
    wi, wo = direction(0.5, 0.2), direction(0.4, 2.9)
    source = PointSource(1.0, 300.0)
    errors = []
    for fov in (20.0, 2.0, 0.2):
        optics = DetectorOptics(1e-3, fov)
        phi = point_source_power(source, optics, 30.0, model.eval, wi, wo)
        errors.append(abs(phi / radiant_power(source, optics, model.eval(wi, wo), wi, wo) - 1))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-6


@pytest.mark.parametrize("theta_o", [0.3, 0.8, 1.2, 1.5])
def test_seen_area_is_clipped_by_the_sample(theta_o):
    """A far source (uniform E, fixed incidence) and a Lambertian sample: Φ / Φ_ideal is
    Area(seen ∩ sample) / Area(seen), which `footprint_fraction` gives independently (a
    huge beam at normal incidence lights everything: η = Area(seen ∩ disc)/(πD²/4))."""
    wi, wo = NORMAL, direction(theta_o, 0.7)
    optics, sample = DetectorOptics(1e-3, 25.0), 30.0
    source = PointSource(1.0, 1e7)
    phi = point_source_power(source, optics, sample, LAMBERT.eval, wi, wo)
    ideal = radiant_power(source, optics, 0.8 / math.pi, wi, wo)
    big = 1000.0
    area = footprint_fraction(big, 25.0, sample, wi, wo) * math.pi * big**2 / 4
    seen = math.pi * 25.0**2 / (4 * math.cos(theta_o))
    assert phi / ideal == pytest.approx(area / seen, rel=1e-9)
    assert (phi / ideal < 1 - 1e-6) == (25.0 / math.cos(theta_o) > sample)


def test_grazing_and_extremes_are_finite_without_warnings():
    optics = DetectorOptics(1e-3, 25.0)
    model = brdf.create("cook_torrance", alpha=0.05, f0=(0.9, 0.6, 0.3))
    near = PointSource(1.0, 10.0)  # inside the sample's radius: at grazing it lies on it
    for wi, wo in [(GRAZING, NORMAL), (NORMAL, GRAZING), (GRAZING, GRAZING)]:
        assert np.all(point_source_power(near, optics, 30.0, model.eval, wi, wo) == 0.0)
    for wi, wo in [(NORMAL, NORMAL), (direction(0.6, 0.0), direction(0.6, math.pi))]:
        phi = point_source_power(near, optics, 30.0, model.eval, wi, wo)
        assert phi.shape == (3,)
        assert np.all(np.isfinite(phi) & (phi > 0))
    wi = direction(math.pi / 2 - 1e-9, 0.0)
    phi = point_source_power(near, optics, 30.0, model.eval, wi, NORMAL)
    assert np.all((phi >= 0) & (phi < 1e-9))


def test_shapes_broadcasting_and_blocks():
    rng = np.random.default_rng(4)
    wi = hemisphere(rng, 3).reshape(3, 1, 3)
    wo = hemisphere(rng, 4).reshape(1, 4, 3)
    source, optics = PointSource(1.0, 200.0), DetectorOptics(1e-3, 20.0)
    model = brdf.create("lambert", albedo=(0.2, 0.4, 0.6))
    phi = point_source_power(source, optics, 30.0, model.eval, wi, wo)
    assert phi.shape == (3, 4, 3)
    one = point_source_power(source, optics, 30.0, model.eval, wi[2, 0], wo[0, 1])
    np.testing.assert_allclose(phi[2, 1], one, rtol=1e-14)
    # many pairs: processed in blocks, same values as one at a time
    many_wi, many_wo = hemisphere(rng, 300), hemisphere(rng, 300)
    grey = LAMBERT.eval
    all_at_once = point_source_power(source, optics, 30.0, grey, many_wi, many_wo)
    assert all_at_once[123] == point_source_power(
        source, optics, 30.0, grey, many_wi[123], many_wo[123]
    )


def test_invalid_inputs_raise():
    optics = DetectorOptics(1e-3, 20.0)
    with pytest.raises(DomainError, match="needs a PointSource"):
        point_source_power(CollimatedSource(1.0, 5.0), optics, 30.0, LAMBERT.eval, NORMAL, NORMAL)  # type: ignore[arg-type]
    with pytest.raises(DomainError, match="sample_diameter_mm"):
        point_source_power(PointSource(1.0, 50.0), optics, -3.0, LAMBERT.eval, NORMAL, NORMAL)
    with pytest.raises(DomainError, match="order"):
        point_source_power(
            PointSource(1.0, 50.0), optics, 30.0, LAMBERT.eval, NORMAL, NORMAL, order=(0, 4)
        )
