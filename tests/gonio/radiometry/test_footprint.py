"""footprint_fraction: exact 1 where the lit ellipse fits, the kick-in angle of the
ellipse geometry, monotone toward grazing, agreement with Monte Carlo and with a dense
independent quadrature, 0 at grazing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.errors import DomainError
from gonio.radiometry import footprint_fraction, seen_fits_sample
from gonio.rig.constraints import footprint_ok
from tests.gonio.radiometry.helpers import GRAZING, NORMAL, direction, hemisphere

D, F, S = 6.0, 25.0, 30.0  # the shipped rigs' beam, field of view and sample (mm)


def _regions(d, f, s, wi, wo, x):
    """Indicators at sample-plane points x (..., 2) of the seen ellipse and the disc."""
    co = wo[2]
    eo = wo[:2] / np.hypot(*wo[:2]) if np.hypot(*wo[:2]) > 0 else np.array([1.0, 0.0])
    along, across = x @ eo, x @ np.array([-eo[1], eo[0]])
    seen = (along * 2 * co / f) ** 2 + (across * 2 / f) ** 2 <= 1.0
    return seen & (np.sum(x * x, axis=-1) <= (s / 2) ** 2)


def _lit_points(d, wi, u):
    """Map points u of the unit disc onto the lit ellipse."""
    ei = wi[:2] / np.hypot(*wi[:2]) if np.hypot(*wi[:2]) > 0 else np.array([1.0, 0.0])
    ep = np.array([-ei[1], ei[0]])
    return (d / (2 * wi[2])) * u[..., :1] * ei + (d / 2) * u[..., 1:] * ep


def _monte_carlo(d, f, s, wi, wo, n=1_000_000, seed=0):
    rng = np.random.default_rng(seed)
    r, t = np.sqrt(rng.random(n)), 2 * np.pi * rng.random(n)
    u = np.stack([r * np.cos(t), r * np.sin(t)], axis=-1)
    return float(np.mean(_regions(d, f, s, wi, wo, _lit_points(d, wi, u))))


def _dense_polar(d, f, s, wi, wo, n=200_000):
    """η = (1/2π) ∮ min(1, r_seen², r_disc²) dβ in the lit ellipse's unit-disc coordinates,
    midpoint rule with n nodes (kinks: error O(n⁻²) ~ 1e-10)."""
    beta = (np.arange(n) + 0.5) * 2 * np.pi / n
    u = np.stack([np.cos(beta), np.sin(beta)], axis=-1)
    x = _lit_points(d, wi, u)  # the lit ellipse's boundary points, direction β
    co = wo[2]
    eo = wo[:2] / np.hypot(*wo[:2]) if np.hypot(*wo[:2]) > 0 else np.array([1.0, 0.0])
    along, across = x @ eo, x @ np.array([-eo[1], eo[0]])
    q_seen = (along * 2 * co / f) ** 2 + (across * 2 / f) ** 2
    q_disc = np.sum(x * x, axis=-1) / (s / 2) ** 2
    return float(np.mean(np.minimum(1.0, 1.0 / np.maximum(q_seen, q_disc))))


def _kick_in(d, f, s, wo, phi_i=0.0):
    """Bisect the largest θi with η = 1 (wo fixed)."""
    lo, hi = 0.0, math.pi / 2
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if footprint_fraction(d, f, s, direction(mid, phi_i), wo) < 1.0:
            hi = mid
        else:
            lo = mid
    return lo


@pytest.mark.parametrize(
    ("d", "f", "s", "wo", "phi_i", "closed_form"),
    [
        # the sample alone (field of view huge): D / cos θi = S
        (6.0, 1000.0, 30.0, NORMAL, 0.0, math.acos(6.0 / 30.0)),
        (6.0, 1000.0, 30.0, direction(1.0, 2.0), 0.7, math.acos(6.0 / 30.0)),
        # the field of view alone, seen ellipse along the same axis: D/cos θi = F/cos θo
        (6.0, 25.0, 1000.0, direction(math.pi / 3, math.pi), 0.0, math.acos(6 * 0.5 / 25)),
        # the field of view across the lit ellipse: D/(2 cos θi) = F/2
        (6.0, 25.0, 1000.0, direction(math.pi / 3, math.pi / 2), 0.0, math.acos(6.0 / 25.0)),
    ],
    ids=["sample_normal_view", "sample_oblique_view", "fov_along", "fov_across"],
)
def test_kick_in_angle_matches_the_ellipse_geometry(d, f, s, wo, phi_i, closed_form):
    theta = _kick_in(d, f, s, wo, phi_i)
    assert theta == pytest.approx(closed_form, abs=1e-9)
    assert footprint_fraction(d, f, s, direction(closed_form - 1e-9, phi_i), wo) == 1.0
    assert footprint_fraction(d, f, s, direction(closed_form + 1e-6, phi_i), wo) < 1.0


@settings(max_examples=100)
@given(st.integers(0, 2**32 - 1))
def test_exactly_one_wherever_footprint_ok_and_at_most_one_elsewhere(seed):
    rng = np.random.default_rng(seed)
    wi, wo = hemisphere(rng, 200), hemisphere(rng, 200)
    d, f, s = rng.uniform(2, 10), rng.uniform(5, 40), rng.uniform(10, 50)
    eta = footprint_fraction(d, f, s, wi, wo)
    ok = footprint_ok(wi, wo, d, s, f)
    assert np.all(eta[ok] == 1.0)
    assert np.all((eta >= 0.0) & (eta <= 1.0))
    assert np.all(eta[~ok] < 1.0 + 0.0)


def test_monotone_decreasing_toward_grazing():
    theta = np.linspace(0.0, math.pi / 2, 2001)
    for wo in (NORMAL, direction(0.5, math.pi), direction(1.2, 1.0), direction(1.4, 0.3)):
        for phi_i in (0.0, 0.8, 2.0):
            eta = footprint_fraction(D, F, S, direction(theta, phi_i), wo)
            assert np.all(np.diff(eta) <= 1e-15)
            assert eta[0] == 1.0
            assert eta[-1] < 1e-14  # cos(fl(π/2)) = 6e-17, not 0


def test_zero_at_exact_grazing_and_the_strip_limit_within_1e_9():
    for wo in (NORMAL, GRAZING, direction(0.7, 2.0)):
        assert footprint_fraction(D, F, S, GRAZING, wo) == 0.0
    # Near grazing the lit ellipse is a strip |y| ≤ D/2 of area πD²/(4 cos θi): with a
    # normal view (seen circle of radius F/2 < S/2), η / cos θi → A_strip∩circle / (πD²/4).
    rho, h = F / 2, D / 2
    strip_in_circle = 2 * (h * math.sqrt(rho**2 - h**2) + rho**2 * math.asin(h / rho))
    limit = strip_in_circle / (math.pi * D**2 / 4)
    for eps in (1e-5, 1e-7, 1e-9, 1e-12):
        wi = direction(math.pi / 2 - eps, 0.4)
        eta = footprint_fraction(D, F, S, wi, NORMAL)
        assert eta / wi[2] == pytest.approx(limit, rel=1e-8)
    # a grazing view: the detector's seen ellipse degenerates to a strip ⟂ its azimuth
    assert footprint_fraction(D, F, S, NORMAL, GRAZING) == 1.0
    rho, h = D / 2, 2.0  # lit circle of radius 3 against the strip |y| ≤ F/2 = 2
    clipped = 2 * (h * math.sqrt(rho**2 - h**2) + rho**2 * math.asin(h / rho))
    eta = footprint_fraction(D, 4.0, S, NORMAL, GRAZING)
    assert eta == pytest.approx(clipped / (math.pi * rho**2), rel=1e-12)


CONFIGS = [
    (D, F, S, direction(math.radians(80), 0.0), direction(math.radians(30), math.pi)),
    (D, F, S, direction(math.radians(85), 0.35), direction(math.radians(70), 1.75)),
    (D, 10.0, S, direction(math.radians(88), 0.0), direction(math.radians(60), 0.8)),
    (D, 10.0, S, direction(math.radians(75), 0.0), direction(math.radians(80), math.pi / 2)),
]


@pytest.mark.parametrize(("d", "f", "s", "wi", "wo"), CONFIGS)
def test_agrees_with_monte_carlo(d, f, s, wi, wo):
    eta = footprint_fraction(d, f, s, wi, wo)
    assert 0.05 < eta < 1.0
    assert eta == pytest.approx(_monte_carlo(d, f, s, wi, wo), abs=2e-3)


@pytest.mark.parametrize(("d", "f", "s", "wi", "wo"), CONFIGS)
def test_agrees_with_a_dense_independent_quadrature(d, f, s, wi, wo):
    eta = footprint_fraction(d, f, s, wi, wo)
    assert eta == pytest.approx(_dense_polar(d, f, s, wi, wo), abs=1e-9)


def test_shapes_and_broadcasting():
    rng = np.random.default_rng(9)
    wi = direction(np.linspace(1.2, 1.55, 6), 0.3).reshape(2, 3, 1, 3)
    wo = hemisphere(rng, 4).reshape(1, 1, 4, 3)
    eta = footprint_fraction(D, 10.0, S, wi, wo)
    assert eta.shape == (2, 3, 4)
    assert eta[1, 2, 3] == footprint_fraction(D, 10.0, S, wi[1, 2, 0], wo[0, 0, 3])
    assert np.ndim(footprint_fraction(D, F, S, NORMAL, NORMAL)) == 0


def test_seen_fits_sample_is_f_over_cos_theta_o_at_most_s():
    theta = np.linspace(0, math.pi / 2, 91)
    fits = seen_fits_sample(F, S, direction(theta))
    np.testing.assert_array_equal(fits, F / np.maximum(np.cos(theta), 1e-300) <= S)
    assert not seen_fits_sample(F, S, GRAZING)


@pytest.mark.parametrize("bad", [0.0, -2.0, math.nan, math.inf])
def test_invalid_diameters_raise(bad):
    for args in [(bad, F, S), (D, bad, S), (D, F, bad)]:
        with pytest.raises(DomainError, match="must be a positive finite number"):
            footprint_fraction(*args, NORMAL, NORMAL)
