"""`CalibrationSeries`: the reference rate interpolated through the calibrations (a
spline that follows a bending drift), the dark readings' rounding error
(`rounding_var`), and the factor of a variance estimated from few degrees of freedom
(`student_variance`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import norm
from scipy.stats import t as student_t

from gonio.radiometry import series as series_module
from gonio.radiometry.series import (
    NOISE_GAIN,
    CalibrationSeries,
    rounding_var,
    student_variance,
)

ALBEDO = 0.99
ZENITH = np.array([0.0, 0.0, 1.0])
AT_45 = np.array([-math.sqrt(0.5), 0.0, math.sqrt(0.5)])


def series(t, rate, *, dark_rounding=None, rate_var=None) -> CalibrationSeries:
    t = np.asarray(t, dtype=np.float64)
    k = len(t)
    return CalibrationSeries(
        albedo=ALBEDO,
        source_kind="collimated",
        wi=ZENITH,
        wo=AT_45,
        t=t,
        dark_rate=np.zeros(k),
        dark_rate_var=np.zeros(k),
        rate=np.asarray(rate, dtype=np.float64),
        rate_var=np.zeros(k) if rate_var is None else np.asarray(rate_var, dtype=np.float64),
        noise_a=0.0,
        noise_b=0.0,
        dark_rounding=None if dark_rounding is None else np.asarray(dark_rounding, float),
    )


def drift(t):
    """A lamp's power: 2 %/h and a 0.5 % oscillation over 15 min."""
    return 1e5 * (1 + 0.02 * t / 3600 + 0.005 * np.sin(2 * np.pi * t / 900))


def test_a_drift_that_bends_between_calibrations_divides_out():
    """Samples of the reference's own geometry read f = ρ/π between calibrations two
    minutes apart: a straight line between them missed the drift's bend by up to 4.3e-4
    and by −2.6e-5 on average over the run (the spline: 5e-5 at the ends, 8e-6 inside,
    6e-7 on average)."""
    t_cal = np.arange(0.0, 2401.0, 120.0)
    cal = series(t_cal, drift(t_cal))
    t = np.linspace(0.0, 2400.0, 997)
    exposure = 0.05
    f, _ = cal.brdf(
        drift(t) * exposure,
        np.zeros(t.size),
        np.ones(t.size, dtype=int),
        np.full(t.size, exposure),
        np.tile(ZENITH, (t.size, 1)),
        np.tile(AT_45, (t.size, 1)),
        t,
    )
    np.testing.assert_allclose(f, ALBEDO / math.pi, rtol=6e-5)
    inside = (t > 240) & (t < 2160)
    np.testing.assert_allclose(f[inside], ALBEDO / math.pi, rtol=1e-5)
    assert abs(np.mean(f) * math.pi / ALBEDO - 1) < 2e-6


@pytest.mark.parametrize("k", [1, 2, 3, 4, 9])
def test_weights_sum_to_one_and_hold_beyond_the_ends(k):
    t_cal = np.sort(np.random.default_rng(k).uniform(0, 100, k)) + np.arange(k)
    cal = series(t_cal, np.ones(k))
    t = np.linspace(-10, 120, 50)
    w = cal.weights(t)
    assert w.shape == (50, k)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(cal.weights(t_cal), np.eye(k), atol=1e-12)
    np.testing.assert_allclose(
        w[t < t_cal[0]], cal.weights(t_cal[:1]).repeat((t < t_cal[0]).sum(), 0)
    )
    np.testing.assert_allclose(
        w[t > t_cal[-1]], cal.weights(t_cal[-1:]).repeat((t > t_cal[-1]).sum(), 0)
    )


def test_a_cubic_drift_is_followed_exactly():
    t_cal = np.array([0.0, 40.0, 75.0, 120.0, 160.0, 200.0])
    cubic = lambda t: 1e4 * (1 + 1e-3 * t - 2e-5 * t**2 + 1e-7 * t**3)  # noqa: E731
    t = np.linspace(0, 200, 77)
    np.testing.assert_allclose(series(t_cal, cubic(t_cal)).rate_at(t), cubic(t), rtol=1e-12)
    parabola = lambda t: 1e4 * (1 + 1e-3 * t - 2e-5 * t**2)  # noqa: E731
    three = series(t_cal[:3], parabola(t_cal[:3]))
    np.testing.assert_allclose(three.rate_at(t[t <= 75]), parabola(t[t <= 75]), rtol=1e-12)


def bias_mean_square(sigma: float) -> float:
    """E over x uniform in a code of (E[round(x + n)] − x)², n ~ N(0, σ²), by brute sum."""
    x = (np.arange(4000) + 0.5) / 4000
    if sigma == 0:
        return float(np.mean((np.round(x) - x) ** 2))
    k = np.arange(-8, 10)[None, :]
    p = norm.cdf((k + 0.5 - x[:, None]) / sigma) - norm.cdf((k - 0.5 - x[:, None]) / sigma)
    return float(np.mean(((k * p).sum(axis=1) - x) ** 2))


@pytest.mark.parametrize("sigma", [0.0, 0.05, 0.137, 0.175, 0.3])
def test_rounding_var_is_the_mean_square_rounding_bias(sigma):
    assert rounding_var(sigma) == pytest.approx(bias_mean_square(sigma), rel=2e-3, abs=1e-9)


def test_rounding_var_at_the_limits():
    assert rounding_var(0.0) == pytest.approx(1 / 12, rel=1e-3)
    assert rounding_var(0.5) < 1e-5
    assert rounding_var([0.1, 0.2]).shape == (2,)


def test_the_dark_rounding_error_counts_in_sigma_as_s_and_S_share_it():
    """f ∝ (C/e − d)/(R/e − d): an error δ of d moves f by (s − S)/(S s)·δ of f; at
    s = S it cancels."""
    t_cal = np.array([0.0, 100.0])
    cal = series(t_cal, [1e5, 1e5], dark_rounding=[10.0, 10.0])
    exposure, t = 0.1, np.array([50.0, 50.0])
    rates = np.array([1e5, 2.5e4])  # s = S, and s = S/4
    f, sigma = cal.brdf(
        rates * exposure,
        np.zeros(2),
        np.full(2, 16),
        np.full(2, exposure),
        np.tile(ZENITH, (2, 1)),
        np.tile(AT_45, (2, 1)),
        t,
    )
    assert sigma[0] == 0.0
    assert sigma[1] / f[1] == pytest.approx(10.0 * (1e5 - 2.5e4) / (1e5 * 2.5e4))


def test_a_calibration_moments_after_another_keeps_the_line():
    """A spline through readings 100 s, 100 s and 1 s apart would multiply their noise
    (Σ w² in the hundreds): the line holds there, its gain at most 1."""
    uneven = series([0.0, 100.0, 200.0, 201.0], np.ones(4))
    t = np.linspace(0.0, 201.0, 500)
    w = uneven.weights(t)
    assert np.all(w >= 0) and np.max(np.sum(w**2, axis=1)) <= 1.0 + 1e-12
    regular = series([0.0, 100.0, 200.0, 300.0], np.ones(4)).weights(t)
    assert np.any(regular < 0) and np.max(np.sum(regular**2, axis=1)) <= NOISE_GAIN


def test_blocks_of_samples_give_the_whole_runs_values(monkeypatch: pytest.MonkeyPatch):
    """The samples × calibrations weights are formed a block of samples at a time (a run
    of 10⁶ samples and 10³ calibrations would need 8 GB at once): blocks of 7 samples
    give the values and σ of one block (to rounding: the products sum in another order)."""
    t_cal = np.arange(0.0, 2401.0, 120.0)
    cal = series(
        t_cal,
        drift(t_cal),
        dark_rounding=np.full(t_cal.size, 3.0),
        rate_var=np.full(t_cal.size, 4.0),
    )
    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0.0, 2400.0, 101))
    args = (
        rng.uniform(1e3, 1e4, t.size),
        rng.uniform(1.0, 5.0, t.size),
        np.full(t.size, 4),
        np.full(t.size, 0.05),
        np.tile(ZENITH, (t.size, 1)),
        np.tile(AT_45, (t.size, 1)),
        t,
    )
    whole = cal.brdf(*args)
    monkeypatch.setattr(series_module, "BLOCK_ENTRIES", 7 * t_cal.size)
    blocks = cal.brdf(*args)
    for a, b in zip(whole, blocks, strict=True):
        np.testing.assert_allclose(b, a, rtol=1e-14)
    empty = cal.brdf(*(a[:0] for a in args))
    assert empty[0].shape == empty[1].shape == (0,)


@given(st.floats(min_value=2.0, max_value=1e6, exclude_min=True))
def test_student_variance_is_that_of_students_t(dof: float) -> None:
    """ν/(ν − 2) is the variance of Student's t (scipy's), above 1 and falling to 1."""
    factor = student_variance(dof)
    assert factor == pytest.approx(float(student_t.var(dof)), rel=1e-9)
    assert factor > 1.0 and student_variance(2.0 * dof) < factor


def test_student_variance_without_a_finite_one() -> None:
    assert student_variance(math.inf) == 1.0
    assert student_variance(2.0) == math.inf and student_variance(1.0) == math.inf
