"""Counts → BRDF with no effects recovers the model's value to 1e-12 relative, through
the absolute inverse and through the reference calibration, over the pairs reachable on
both shipped rigs, for both source types and several models (grey and RGB)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.radiometry import (
    CollimatedSource,
    DetectorOptics,
    PointSource,
    ReferenceCalibration,
    brdf_from_power,
    electrons,
    power_from_electrons,
    radiant_power,
    relative_geometry,
    source_kind,
)
from gonio.rig.model import Rig
from tests.gonio.radiometry.helpers import GRAZING, MODELS, NORMAL, direction, hemisphere


@pytest.fixture(scope="module")
def pairs(rigs: dict[str, Rig]) -> tuple[np.ndarray, np.ndarray]:
    """3000 uniform pairs, those reachable on both shipped rigs kept."""
    rng = np.random.default_rng(2024)
    wi, wo = hemisphere(rng, 3000), hemisphere(rng, 3000)
    keep = np.ones(len(wi), dtype=bool)
    for rig in rigs.values():
        keep &= rig.reachable(wi, wo)[0]
    return wi[keep], wo[keep]


REF_WI, REF_WO = direction(math.radians(8.0), 0.0), direction(math.radians(45.0), math.pi)
REFERENCE = brdf.create("lambert", albedo=0.99)


def test_the_pair_set_is_large_and_reachable_on_both_rigs(rigs, pairs):
    wi, wo = pairs
    assert len(wi) > 1500  # about 60 % of uniform pairs survive both rigs
    for rig in rigs.values():
        assert rig.reachable(wi, wo)[0].all()
        assert rig.reachable(REF_WI[None], REF_WO[None])[0].all()


def _counts(source, optics, f, wi, wo, exposure, responsivity, gain):
    """The forward chain with no effects: f → Φ → electrons → counts (ADC gain e⁻/count)."""
    power = radiant_power(source, optics, f, wi, wo)
    return electrons(power, exposure, responsivity) / gain


instruments = st.tuples(
    st.floats(1e-2, 1e3),  # E0 (W/m²) or I (W/sr)
    st.floats(1.0, 20.0),  # beam diameter (mm)
    st.floats(100.0, 3000.0),  # source distance (mm)
    st.floats(1e-5, 1e-1),  # aperture (sr)
    st.floats(2.0, 40.0),  # field of view (mm)
    st.floats(1e-4, 10.0),  # exposure (s)
    st.floats(0.05, 1.0),  # responsivity (A/W)
    st.floats(0.1, 100.0),  # ADC gain (e⁻/count)
)


@pytest.mark.parametrize("model_name", list(MODELS))
@pytest.mark.parametrize("kind", ["collimated", "point"])
@settings(max_examples=15)
@given(instrument=instruments)
def test_counts_to_brdf_recovers_the_model(pairs, model_name, kind, instrument):
    wi, wo = pairs
    level, beam, distance, aperture, fov, exposure, responsivity, gain = instrument
    source = CollimatedSource(level, beam) if kind == "collimated" else PointSource(level, distance)
    optics = DetectorOptics(aperture, fov)
    model = MODELS[model_name]
    f = model.eval(wi, wo)
    assert np.all(f > 0.0)
    counts = _counts(source, optics, f, wi, wo, exposure, responsivity, gain)

    # absolute inverse: counts → electrons → power → f
    power = power_from_electrons(counts * gain, exposure, responsivity)
    np.testing.assert_allclose(brdf_from_power(power, source, optics, wi, wo), f, rtol=1e-12)

    # reference calibration: a 99 % Lambertian read through the same chain, another exposure
    ref_exposure = 0.37 * exposure
    ref_counts = _counts(
        source,
        optics,
        REFERENCE.eval(REF_WI, REF_WO),
        REF_WI,
        REF_WO,
        ref_exposure,
        responsivity,
        gain,
    )
    calibration = ReferenceCalibration.from_counts(
        0.99, ref_counts, ref_exposure, REF_WI, REF_WO, source_kind(source)
    )
    recovered = calibration.brdf_from_counts(counts, exposure, wi, wo)
    assert recovered.shape == f.shape
    np.testing.assert_allclose(recovered, f, rtol=1e-12)


def test_calibration_formula_and_dark_subtraction():
    """f = (ρ/π)(s/s_ref)(g_ref/g) with g = cos θo (collimated), cos θi (point); the
    dark counts are subtracted before dividing by the exposure."""
    wi, wo = direction(0.5, 0.2), direction(0.9, 2.5)
    for kind, g, g_ref in [
        ("collimated", math.cos(0.9), REF_WO[2]),
        ("point", math.cos(0.5), REF_WI[2]),
    ]:
        cal = ReferenceCalibration(0.99, 2000.0, REF_WI, REF_WO, kind)
        expected = 0.99 / math.pi * (500.0 / 2000.0) * g_ref / g
        assert cal.brdf(500.0, wi, wo) == pytest.approx(expected, rel=1e-15)
        assert cal.brdf_from_counts(1100.0, 2.0, wi, wo, dark_counts=100.0) == pytest.approx(
            expected, rel=1e-15
        )
        assert relative_geometry(kind, wi, wo) == pytest.approx(g, rel=1e-15)


def test_rgb_calibration_per_channel():
    """A 3-channel detector: per-channel reference rates and albedos."""
    cal = ReferenceCalibration((0.98, 0.99, 0.97), (100.0, 200.0, 400.0), NORMAL, NORMAL, "point")
    wi, wo = hemisphere(np.random.default_rng(5), 6), hemisphere(np.random.default_rng(6), 6)
    rates = np.full((6, 3), 100.0)
    out = cal.brdf(rates, wi, wo)
    assert out.shape == (6, 3)
    expected = np.array([0.98, 0.99 / 2, 0.97 / 4]) / math.pi / wi[:, 2:3]
    np.testing.assert_allclose(out, expected, rtol=1e-14)


@pytest.mark.parametrize(
    ("wi", "wo"),
    [
        (NORMAL, NORMAL),  # normal incidence, retro-reflection at the pole
        (direction(1.1, 0.4), direction(1.1, 0.4)),  # retro-reflection
        (direction(0.6, 0.3), direction(0.6, 0.3 + math.pi)),  # mirror
        (direction(math.pi / 2 - 1e-9, 0.0), direction(0.3, 2.0)),  # within 1e-9 of grazing
        (direction(0.3, 2.0), direction(math.pi / 2 - 1e-9, 1.0)),
    ],
    ids=["normal", "retro", "mirror", "near_grazing_light", "near_grazing_view"],
)
@pytest.mark.parametrize("source", [CollimatedSource(100.0, 6.0), PointSource(2.0, 500.0)])
def test_named_extreme_pairs_round_trip(wi, wo, source):
    optics = DetectorOptics(1e-3, 20.0)
    for model in MODELS.values():
        f = model.eval(wi, wo)
        power = radiant_power(source, optics, f, wi, wo)
        np.testing.assert_allclose(brdf_from_power(power, source, optics, wi, wo), f, rtol=1e-12)
        cal = ReferenceCalibration(0.99, 1.0, NORMAL, NORMAL, source_kind(source))
        ref_power = radiant_power(source, optics, 0.99 / math.pi, NORMAL, NORMAL)
        np.testing.assert_allclose(cal.brdf(power / ref_power, wi, wo), f, rtol=1e-12)


@pytest.mark.parametrize("source", [CollimatedSource(100.0, 6.0), PointSource(2.0, 500.0)])
def test_exactly_grazing_pairs_give_no_warnings_and_finite_values(source):
    optics = DetectorOptics(1e-3, 20.0)
    model = MODELS["cook_torrance_rgb"]
    for wi, wo in [(GRAZING, NORMAL), (NORMAL, GRAZING), (GRAZING, GRAZING), (GRAZING, -GRAZING)]:
        f = model.eval(wi, wo)
        power = radiant_power(source, optics, f, wi, wo)
        back = brdf_from_power(power, source, optics, wi, wo)
        assert np.all(np.isfinite(back))
        cal = ReferenceCalibration(0.99, 1.0, NORMAL, NORMAL, source_kind(source))
        assert np.all(np.isfinite(cal.brdf(power, wi, wo)))
