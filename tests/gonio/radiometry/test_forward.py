"""detector_power: only the effects asked for, each reducing to its building block."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gonio.brdf as brdf
from gonio.errors import DomainError
from gonio.radiometry import (
    CollimatedSource,
    DetectorOptics,
    PointSource,
    aperture_integral,
    detector_power,
    footprint_fraction,
    point_source_power,
    prefactor,
    radiant_power,
)
from tests.gonio.radiometry.helpers import NORMAL, direction, hemisphere

MODEL = brdf.create("cook_torrance", alpha=0.1, f0=(0.9, 0.6, 0.3), kd=0.05)
BEAM, LAMP = CollimatedSource(200.0, 6.0), PointSource(2.0, 400.0)
OPTICS = DetectorOptics(1e-3, 25.0)
RNG = np.random.default_rng(11)
WI, WO = hemisphere(RNG, 40).reshape(5, 8, 3), hemisphere(RNG, 40).reshape(5, 8, 3)


@pytest.mark.parametrize("source", [BEAM, LAMP], ids=["collimated", "point"])
def test_no_effects_is_the_ideal_chain(source):
    expected = radiant_power(source, OPTICS, MODEL.eval(WI, WO), WI, WO)
    np.testing.assert_array_equal(detector_power(source, OPTICS, MODEL.eval, WI, WO), expected)


def test_collimated_effects_compose():
    k = prefactor(BEAM, OPTICS, WI)[..., None]
    eta = footprint_fraction(6.0, 25.0, 30.0, WI, WO)[..., None]
    angular = aperture_integral(MODEL.eval, WI, WO, 1e-3, "cos")
    ideal = radiant_power(BEAM, OPTICS, MODEL.eval(WI, WO), WI, WO)
    kw = {"sample_diameter_mm": 30.0}
    np.testing.assert_allclose(
        detector_power(BEAM, OPTICS, MODEL.eval, WI, WO, footprint=True, **kw), ideal * eta
    )
    np.testing.assert_allclose(
        detector_power(BEAM, OPTICS, MODEL.eval, WI, WO, aperture_integration=True), k * angular
    )
    both = detector_power(
        BEAM, OPTICS, MODEL.eval, WI, WO, footprint=True, aperture_integration=True, **kw
    )
    np.testing.assert_allclose(both, k * angular * eta)


def test_point_source_effects_compose():
    wi, wo = WI[0, :3], WO[0, :3]
    spatial = point_source_power(LAMP, OPTICS, 30.0, MODEL.eval, wi, wo)
    got = detector_power(LAMP, OPTICS, MODEL.eval, wi, wo, footprint=True, sample_diameter_mm=30.0)
    np.testing.assert_array_equal(got, spatial)
    k = prefactor(LAMP, OPTICS, wi)[..., None]
    angular = aperture_integral(MODEL.eval, wi, wo, 1e-3, "one")
    got = detector_power(LAMP, OPTICS, MODEL.eval, wi, wo, aperture_integration=True)
    np.testing.assert_allclose(got, k * angular)
    both = detector_power(
        LAMP,
        OPTICS,
        MODEL.eval,
        wi,
        wo,
        footprint=True,
        aperture_integration=True,
        sample_diameter_mm=30.0,
        spatial_order=(4, 6),
        aperture_order=(4, 8),
    )
    assert both.shape == (3, 3)
    # a smooth lobe: averaging over 1e-3 sr changes little, so both ≈ the spatial value
    np.testing.assert_allclose(both, spatial, rtol=5e-3)


def test_nested_combination_for_a_far_source_and_a_small_field_is_the_aperture_alone():
    """Far source, tiny field of view on the sample: the spatial integral is the ideal
    one, so both effects together equal the aperture effect alone."""
    wi, wo = direction(0.5, 0.0), direction(0.5, math.pi)  # the mirror pair
    source, optics = PointSource(1.0, 1e6), DetectorOptics(1e-3, 0.5)
    sharp = brdf.create("cook_torrance", alpha=0.02, f0=0.9)
    both = detector_power(
        source,
        optics,
        sharp.eval,
        wi,
        wo,
        footprint=True,
        aperture_integration=True,
        sample_diameter_mm=30.0,
    )
    aperture_only = detector_power(source, optics, sharp.eval, wi, wo, aperture_integration=True)
    assert both == pytest.approx(aperture_only, rel=1e-8)
    assert both < 0.9 * detector_power(source, optics, sharp.eval, wi, wo)


def test_footprint_needs_the_sample_size():
    with pytest.raises(DomainError, match="sample_diameter_mm"):
        detector_power(BEAM, OPTICS, MODEL.eval, NORMAL, NORMAL, footprint=True)
