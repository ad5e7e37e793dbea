"""The lock-in model (`sim.virtual.physics.lockin`): its filter's noise bandwidth, the chopped
signal's fundamental, the shot noise it passes, background rejection and overload."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from sim.virtual.physics.lockin import ENBW_TAU, LockIn


@pytest.mark.parametrize("slope", [6, 12, 18, 24])
def test_the_noise_bandwidth_is_that_of_cascaded_rc_stages(slope: int) -> None:
    # ENBW = ∫₀^∞ |H(f)|² df with |H|² = (1 + (2π f τ)²)^-n, for τ = 1.
    n = slope // 6
    enbw, _ = integrate.quad(lambda f: (1 + (2 * math.pi * f) ** 2) ** -n, 0, math.inf)
    assert ENBW_TAU[slope] == pytest.approx(enbw, rel=1e-6)


def test_a_square_wave_fundamental_is_0_45_of_the_signal_and_the_background_is_rejected() -> None:
    lockin = LockIn(time_constant_s=0.01, sensitivity=1e9)
    assert lockin.fundamental == pytest.approx(math.sqrt(2) / math.pi)
    t = np.linspace(0, 1, 200_001)[:-1]  # one chopper period
    for background in (0.0, 5e5):
        current = background + 1e6 * (t < 0.5)
        rms_fundamental = abs(2 * np.mean(current * np.exp(-2j * np.pi * t))) / math.sqrt(2)
        assert rms_fundamental == pytest.approx(lockin.expected(1e6), rel=1e-4)


def test_readings_have_the_expected_mean_and_shot_noise() -> None:
    lockin = LockIn(time_constant_s=0.003, sensitivity=1e9, gain=2.0)
    rng = np.random.default_rng(1)
    signal, background = 4e6, 1e6
    r, overloaded = lockin.read(signal, background, rng, n=40_000)
    assert not overloaded.any()
    sigma = math.sqrt(2 * (0.5 * signal + background) * 5 / 64 / 0.003) * 2.0
    assert lockin.sigma(signal, background) == pytest.approx(sigma)
    assert np.std(r) == pytest.approx(sigma, rel=0.02)  # high SNR: R's spread is X's
    assert np.mean(r) == pytest.approx(lockin.expected(signal), rel=1e-3)
    assert lockin.settle_s == pytest.approx(0.003 * 10.05, rel=1e-3)


def test_a_reading_at_the_sensitivity_overloads_and_is_clipped() -> None:
    lockin = LockIn(time_constant_s=0.01, sensitivity=1.0, gain=1e-6)
    values, overloaded = lockin.read(5e6, 0.0, np.random.default_rng(0), n=3)
    assert overloaded.all() and np.all(values == 1.1)
