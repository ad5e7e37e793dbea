"""gonio.brdf.lobes: values at known points, cut, clamping, broadcasting, ordering."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gonio.brdf import lobes

XIS = (lobes.XI_STANDARD, lobes.XI_29_64, 0.463)
NS = np.array([1.0, 2.0, 16.0, 37.5, 100.0, 256.0, 1000.0, 1e4])


def all_lobes(c: np.ndarray, n: np.ndarray) -> list[np.ndarray]:
    out = [lobes.power_cosine(c, n), lobes.schlick(c, n)]
    for xi in XIS:
        out += [lobes.cosine_quadratic(c, n, xi), lobes.cosine_quadratic(c, n, xi, cut=False)]
    return out


def test_peak_is_one_for_every_lobe() -> None:
    for v in all_lobes(np.ones_like(NS), NS):
        np.testing.assert_array_equal(v, 1.0)


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (lobes.power_cosine(0.5, 2.0), 0.25),
        (lobes.power_cosine(0.9, 37.5), 0.9**37.5),
        (lobes.cosine_quadratic(0.9, 10.0, 0.5), 0.25),  # (5·(−0.1) + 1)²
        (lobes.cosine_quadratic(0.99, 16.0, 29 / 64), (1 - 0.16 * 29 / 64) ** 2),
        (lobes.schlick(0.5, 1.0), 0.5),  # n = 1: F_S = cos ψ
        (lobes.schlick(0.9, 10.0), 0.9 / 1.9),
    ],
)
def test_known_values(value: np.ndarray, expected: float) -> None:
    assert float(value) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("xi", XIS)
def test_zero_crossing_is_the_zero(xi: float) -> None:
    c = lobes.zero_crossing_cos(NS[NS > 3], xi)
    assert np.all(lobes.cosine_quadratic(c, NS[NS > 3], xi, cut=False) < 1e-25)


def test_zero_crossing_for_29_64_is_eq_14() -> None:
    np.testing.assert_allclose(
        lobes.zero_crossing_cos(NS, lobes.XI_29_64), (29 * NS - 64) / (29 * NS), rtol=1e-15
    )


def test_cut_zeroes_only_beyond_the_zero() -> None:
    n, xi = 100.0, 0.463
    z = float(lobes.zero_crossing_cos(n, xi))
    c = np.linspace(0.0, 1.0, 10001)
    cut = lobes.cosine_quadratic(c, n, xi)
    raw = lobes.cosine_quadratic(c, n, xi, cut=False)
    assert np.all(cut[c <= z] == 0.0)
    # The parabola rises again: why Romanyuk et al.'s modified cosine-quadratic model
    # cuts it at its zero.
    assert np.all(raw[c < z - 1e-3] > 0.0)
    np.testing.assert_array_equal(cut[c > z], raw[c > z])


def test_negative_cos_gives_zero() -> None:
    c = np.array([-1.0, -0.5, -1e-12])
    for v in all_lobes(c[:, None], NS):
        np.testing.assert_array_equal(v, 0.0)


def test_broadcasting() -> None:
    c = np.linspace(0.5, 1.0, 3)[:, None]
    n = np.array([16.0, 64.0, 256.0, 1000.0])
    for v in all_lobes(c, n):
        assert v.shape == (3, 4)
        assert v.dtype == np.float64
    xi = np.array([0.45, 0.5])[:, None, None]
    v = lobes.cosine_quadratic(c, n, xi)
    assert v.shape == (2, 3, 4)
    np.testing.assert_array_equal(v[1], lobes.cosine_quadratic(c, n, 0.5))
    assert lobes.power_cosine(0.5, 2).shape == ()


def test_no_floating_point_trouble_at_the_ends() -> None:
    n = np.geomspace(1.0, 1e4, 200)
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        for c in (0.0, 1.0):
            for i, v in enumerate(all_lobes(np.full_like(n, c), n)):
                assert np.all(np.isfinite(v))
                if i < 2 or i % 2 == 0:  # all but the raw (uncut) parabolas
                    assert np.all((v >= 0.0) & (v <= 1.0))
        assert np.all(lobes.epicentre_limit_cos(n) < 1.0)


def test_epicentre_limit_puts_f_b_at_exp_minus_0511() -> None:
    # cos rounded to 1 ulp, raised to n: relative error ≲ n · 1.1e-16 (≈ 1e-12 at n = 1e4).
    np.testing.assert_allclose(
        lobes.power_cosine(lobes.epicentre_limit_cos(NS), NS), math.exp(-0.511), rtol=3e-12
    )


def test_xi_equation_12_solves_the_printed_equation() -> None:
    xi = lobes.xi_equation_12()
    assert -0.71068 * xi + 0.12026 * xi**2 + 1.40119 == pytest.approx(1.098, abs=1e-14)
    assert 0 < xi < 1
    assert round(xi, 3) == 0.463
    assert xi == pytest.approx(0.462875, abs=1e-6)


cos01 = st.floats(0.0, 1.0)
shininess = st.floats(2.0, 1e4)


@given(c=cos01, n=shininess, xi=st.sampled_from(XIS))
def test_lobes_lie_in_unit_interval(c: float, n: float, xi: float) -> None:
    for v in (
        lobes.power_cosine(c, n),
        lobes.schlick(c, n),
        lobes.cosine_quadratic(c, n, xi),
    ):
        assert 0.0 <= float(v) <= 1.0


@given(a=cos01, b=cos01, n=shininess, xi=st.sampled_from(XIS))
def test_lobes_monotone_in_cos(a: float, b: float, n: float, xi: float) -> None:
    lo, hi = min(a, b), max(a, b)
    for f in (
        lobes.power_cosine,
        lobes.schlick,
        lambda c, m: lobes.cosine_quadratic(c, m, xi),
    ):
        assert float(f(lo, n)) <= float(f(hi, n))


@given(c=cos01, n=shininess)
def test_f2_below_f_b_below_schlick(c: float, n: float) -> None:
    """For n ≥ 2: F_2 ≤ F_B ≤ F_S on [0, 1] (ratio F_2/F_B rises, F_S/F_B falls, to 1 at c=1).

    √F_2 = n/2 (c − 1) + 1 is rounded to ~n ulps absolute (it equals c exactly at n = 2).
    """
    f2 = float(lobes.cosine_quadratic(c, n, 0.5))
    fb = float(lobes.power_cosine(c, n))
    fs = float(lobes.schlick(c, n))
    assert math.sqrt(f2) <= math.sqrt(fb) * (1 + 1e-12) + n * 2.3e-16
    assert fb <= fs * (1 + 1e-12)
