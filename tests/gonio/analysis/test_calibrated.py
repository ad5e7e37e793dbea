"""`calibration_series`: the dark readings' rounding to ADC codes, an error shared by
every calibration, from the journaled readings."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from gonio.analysis.calibrated import calibration_series
from gonio.analysis.shared import calibration_error
from gonio.radiometry.series import rounding_var
from gonio.store.read import Event

EXPOSURE = 0.05


def reading(value: float, std: float, n: int = 16, start: float = 0.0) -> dict[str, Any]:
    return {
        "value": value,
        "n": n,
        "saturated": False,
        "std": std,
        "exposure_s": EXPOSURE,
        "started_s": start,
        "ended_s": start + 1.0,
    }


def events(ref: list[tuple[float, float]], dark: list[tuple[float, float]]) -> tuple[Event, ...]:
    out = []
    for k, ((r, rs), (d, ds)) in enumerate(zip(ref, dark, strict=True)):
        data = {
            "albedo": 0.99,
            "source_kind": "collimated",
            "wi": [0.0, 0.0, 1.0],
            "wo": [-math.sqrt(0.5), 0.0, math.sqrt(0.5)],
            "reference": reading(r, rs, start=20.0 * k),
            "dark": reading(d, ds, start=20.0 * k + 1),
        }
        out.append(Event(k, 1, "calibration", None, 20.0 * k, "", data))
    return tuple(out)


def test_whole_code_darks_below_a_code_of_noise_carry_their_rounding():
    """The glossy scene's readings: 16.78 codes of dark with 0.17 codes of noise read 17
    nearly always; the rounding error is the mean square over where the level lies in
    its code, dithered by the dark's own shot noise b·D."""
    cal = events([(16510.0625, 5.3), (16509.8125, 5.1)], [(17.0, 0.0), (16.9375, 0.25)])
    series = calibration_series(cal)
    b = np.mean([5.3**2 / 16493.0625, (5.1**2 - 0.25**2) / 16492.875])
    # as the σ use it, times Student's ν/(ν − 2) of 2·15 degrees of freedom; the rounding's
    # dither from the estimate itself
    assert series.noise_b == pytest.approx(b * 30 / 28)
    expected = np.sqrt(rounding_var(np.sqrt(b * np.array([17.0, 16.9375])))) / EXPOSURE
    np.testing.assert_allclose(series.dark_rounding, expected)
    assert 2.4 < series.dark_rounding[0] < 2.8  # ≈ 0.13 codes, vs 1/√12 = 0.29 undithered
    # the run's scale error: the readings' own errors and the shared rounding, in quadrature
    error = calibration_error(series, np.array([10.0]))
    assert error.weights.shape == (1, 3) and error.relative[-1] == 1.0
    assert error.weights[0, -1] == pytest.approx(series.dark_rounding_at([10.0])[0] / 330000, 0.01)


def test_darks_that_are_not_whole_codes_or_dithered_carry_none():
    series = calibration_series(events([(16510.24, 5.3)] * 2, [(16.78, 0.17)] * 2))
    assert np.all(series.dark_rounding == 0.0)
    assert calibration_error(series, np.array([10.0])).weights.shape == (1, 2)
    dithered = calibration_series(events([(16510.0625, 5.3)] * 2, [(16.8125, 3.0)] * 2))
    assert np.all(dithered.dark_rounding < 1e-6)


def test_each_readings_variance_comes_from_the_pooled_noise_model():
    """A reading's own spread of n exposures is itself uncertain; the noise model pooled
    over the calibrations (a + b·signal per exposure) is the better estimate, expanded by
    Student's ν/(ν − 2) for the 2·15 degrees of freedom it rests on."""
    cal = events([(16510.0625, 5.3), (16509.8125, 4.1)], [(17.0, 0.2), (16.9375, 0.25)])
    series = calibration_series(cal)
    a, b = np.mean([0.2**2, 0.25**2]) * 30 / 28, series.noise_b
    assert series.noise_a == pytest.approx(a)
    assert series.noise_dof == 30
    signal = np.array([16510.0625 - 17.0, 16509.8125 - 16.9375])
    np.testing.assert_allclose(series.rate, signal / EXPOSURE)
    expected = ((a + b * signal) / 16 + a / 16) / EXPOSURE**2
    np.testing.assert_allclose(series.rate_var, expected)
    np.testing.assert_allclose(series.dark_rate_var, a / 16 / EXPOSURE**2)
