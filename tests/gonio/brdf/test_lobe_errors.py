"""gonio.brdf.lobe_errors: Romanyuk et al.'s equation 12 and error figures, recomputed.

The paper is Romanyuk et al.'s modified cosine-quadratic reflectance model.

Tolerances: the integrals and the epicentre maxima are exact up to rounding and
quad's 1e-13 tolerance, so they are checked against independent computations at
1e-10 or better and against the figures quoted in docs/explanations/lobes.md at the last digit
quoted there (half a unit of it).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import integrate

from gonio.brdf import lobe_errors as ls
from gonio.brdf import lobes
from studies.brdf import lobe_grid as lg

LOBES = {lb.name: lb for lb in ls.study_lobes()}


def psi_integrals(n: float, k: float) -> list[float]:
    """Eq 11's inner integrals by quadrature in ψ (no closed form)."""
    lim = math.acos(math.exp(-k / n))
    fs = [
        lambda p: math.cos(p) ** n * math.cos(p) * math.sin(p),
        lambda p: n * n * (math.cos(p) - 1) ** 2 * math.cos(p) * math.sin(p),
        lambda p: 2 * n * (math.cos(p) - 1) * math.cos(p) * math.sin(p),
        lambda p: math.cos(p) * math.sin(p),
    ]
    return [integrate.quad(f, 0.0, lim, epsabs=0.0, epsrel=1e-13)[0] for f in fs]


@pytest.mark.parametrize("n", [16.0, 50.0, 256.0, 1000.0])
def test_inner_closed_forms_match_psi_quadrature(n: float) -> None:
    np.testing.assert_allclose(
        [float(v) for v in ls.inner_integrals(n)], psi_integrals(n, ls.K_PRINTED), rtol=1e-11
    )


def test_equation_12_matches_dblquad() -> None:
    e = ls.equation_12()
    got = [e.left, e.quadratic, e.linear, e.constant]
    k = ls.K_PRINTED
    fs = [
        lambda p, n: math.cos(p) ** n * math.cos(p) * math.sin(p),
        lambda p, n: n * n * (math.cos(p) - 1) ** 2 * math.cos(p) * math.sin(p),
        lambda p, n: 2 * n * (math.cos(p) - 1) * math.cos(p) * math.sin(p),
        lambda p, n: math.cos(p) * math.sin(p),
    ]
    ref = [
        integrate.dblquad(f, 16, 256, 0, lambda n: math.acos(math.exp(-k / n)), epsrel=1e-12)[0]
        for f in fs
    ]
    np.testing.assert_allclose(got, ref, rtol=1e-10)
    assert e.abserr < 1e-13


def test_equation_12_matches_mpmath() -> None:
    mpmath.mp.dps = 30
    k = mpmath.mpf(ls.K_PRINTED)

    def left(n: mpmath.mpf) -> mpmath.mpf:
        return -mpmath.expm1(-k * (n + 2) / n) / (n + 2)

    def quad_coef(n: mpmath.mpf) -> mpmath.mpf:
        u = -mpmath.expm1(-k / n)
        return n * n * (u**3 / 3 - u**4 / 4)

    e = ls.equation_12()
    assert e.left == pytest.approx(float(mpmath.quad(left, [16, 256])), rel=1e-13)
    assert e.quadratic == pytest.approx(float(mpmath.quad(quad_coef, [16, 256])), rel=1e-13)


def test_measured_equation_12() -> None:
    e = ls.equation_12()
    assert (e.left, e.quadratic, e.linear, e.constant) == pytest.approx(
        (1.098479, 0.120383, -0.711158, 1.401664), abs=5e-7
    )
    assert e.xi() == pytest.approx(0.462542, abs=5e-7)
    assert round(e.xi(), 3) == ls.SEED_XI


def test_seed_coefficients_come_from_ln_5_3_not_0511() -> None:
    seed, ln53, k511 = ls.SEED_EQ12, ls.equation_12(ls.K_LN_5_3), ls.equation_12()
    # ln(5/3) reproduces every printed digit ...
    assert round(ln53.left, 3) == seed.left
    assert round(ln53.quadratic, 5) == seed.quadratic
    assert round(ln53.linear, 5) == seed.linear
    assert round(ln53.constant, 5) == seed.constant
    # ... 0.511 misses the last printed digits of all three coefficients.
    assert abs(k511.quadratic - seed.quadratic) > 1e-4
    assert abs(k511.linear - seed.linear) > 4e-4
    assert abs(k511.constant - seed.constant) > 4e-4
    assert ln53.xi() == pytest.approx(0.462554, abs=5e-7)
    assert seed.xi() == pytest.approx(lobes.xi_equation_12(), abs=1e-12)


def test_eq12_root_solves_its_quadratic() -> None:
    e = ls.equation_12()
    x = e.xi()
    assert e.quadratic * x * x + e.linear * x + e.constant == pytest.approx(e.left, abs=1e-14)


def test_29_64_is_two_percent_below_the_root() -> None:
    assert lobes.XI_29_64 / ls.equation_12().xi() - 1 == pytest.approx(-0.0204, abs=5e-5)


@pytest.mark.parametrize("n", [16.0, 100.0, 1000.0])
@pytest.mark.parametrize("name", list(LOBES))
def test_exact_epicentre_max_matches_brute_force(name: str, n: float) -> None:
    lobe = LOBES[name]
    psi = np.linspace(0.0, math.acos(math.exp(-0.511 / n)), 200_001)
    c = np.cos(psi)
    brute = np.max(np.abs(lobe(c, n) / lobes.power_cosine(c, n) - 1))
    exact = float(ls.epicentre_max_relative_error(lobe, n)[0])
    assert exact >= brute - 1e-15
    assert exact == pytest.approx(brute, abs=1e-9)


@given(n=st.floats(3.0, 1e4), t=st.floats(0.0, 1.0), xi=st.floats(0.3, 0.5))
def test_exact_epicentre_max_bounds_every_point(n: float, t: float, xi: float) -> None:
    lobe = ls.Lobe("x", xi)
    c = math.cos(t * math.acos(math.exp(-0.511 / n)))
    d = abs(float(lobe(c, n)) / float(lobes.power_cosine(c, n)) - 1)
    assert d <= float(ls.epicentre_max_relative_error(lobe, n)[0]) + 1e-12


# name: (δ at n=16, max δ over [16, 1000], n → ∞), in %; quoted to 3 decimals.
EPICENTRE = {
    "F_VOL(0.463)": (1.898, 2.836, 2.851),
    "F_VOL(eq12)": (1.839, 2.776, 2.792),
    "F_VOL(29/64)": (1.163, 1.548, 1.563),
    "F_2": (6.599, 7.588, 7.604),
    "F_S": (9.723, 10.312, 10.321),
}


@pytest.mark.parametrize("name", list(EPICENTRE))
def test_measured_epicentre_errors(name: str) -> None:
    lobe = LOBES[name]
    d16, dmax, dinf = EPICENTRE[name]
    assert 100 * float(ls.epicentre_max_relative_error(lobe, 16.0)[0]) == pytest.approx(
        d16, abs=5e-4
    )
    peak, at = ls.epicentre_peak(lobe)
    assert 100 * peak == pytest.approx(dmax, abs=5e-4)
    assert at == pytest.approx(1000.0)
    assert 100 * ls.epicentre_limit_n_inf(lobe) == pytest.approx(dinf, abs=5e-4)
    assert 100 * float(ls.epicentre_max_relative_error(lobe, 1e7)[0]) == pytest.approx(
        dinf, abs=5e-4
    )


def test_seed_19_percent_is_n16_with_xi_0463_not_the_maximum() -> None:
    lobe = LOBES["F_VOL(0.463)"]
    assert round(100 * float(ls.epicentre_max_relative_error(lobe, 16.0)[0]), 1) == 1.9
    n = np.geomspace(16.0, 1000.0, 257)
    curve = ls.epicentre_max_relative_error(lobe, n)[0]
    assert np.all(np.diff(curve) > 0)  # rises with n: 1.9% is the minimum of Fig. 3's curve


def test_improvement_ratios() -> None:
    got = dict(ls.improvement_ratios(LOBES["F_VOL(0.463)"], (LOBES["F_2"], LOBES["F_S"])))
    assert list(got.values()) == pytest.approx([2.68, 3.48, 3.99, 3.64, 5.12, 5.43], abs=5e-3)
    assert all(abs(r - ls.SEED_IMPROVEMENT) > 0.3 for r in got.values())


def test_minimax_xi_beats_the_seed_values() -> None:
    xi, worst = ls.minimax_xi()
    assert xi == pytest.approx(0.45106, abs=5e-5)
    assert 100 * worst == pytest.approx(1.277, abs=5e-4)
    for name in ("F_VOL(0.463)", "F_VOL(29/64)"):
        peak, _ = ls.epicentre_peak(LOBES[name])
        assert worst < peak


def test_eq14_is_the_zero_of_f_vol_29_64_only() -> None:
    n = np.geomspace(16.0, 1e4, 200)
    np.testing.assert_allclose(ls.eq14_psi(n), lg.zero_crossing_psi(n, 29 / 64), rtol=1e-12)
    raw = lobes.cosine_quadratic(np.cos(ls.eq14_psi(n)), n, 29 / 64, cut=False)
    assert np.all(raw < 1e-24)
    raw463 = lobes.cosine_quadratic(np.cos(ls.eq14_psi(n)), n, 0.463, cut=False)
    np.testing.assert_allclose(raw463, (1 - 0.463 * 64 / 29) ** 2, rtol=1e-6)
    assert math.degrees(float(ls.eq14_psi(16.0) - lg.zero_crossing_psi(16.0, 0.463))) == (
        pytest.approx(0.334, abs=5e-4)
    )


def test_inflexion_point() -> None:
    n = np.geomspace(16.0, 1000.0, 50)
    p = ls.inflexion_psi(n)
    for s in (-1.0, 1.0):  # (cos^n)'' = n cos^(n−2) ((n−1) sin² − cos²) changes sign there
        q = p * (1 + s * 1e-6)
        second = n * np.cos(q) ** (n - 2) * ((n - 1) * np.sin(q) ** 2 - np.cos(q) ** 2)
        assert np.all(np.sign(second) == s)
    h = 1e-4  # and by finite differences of cos^n itself
    fd = (np.cos(p + h) ** n - 2 * np.cos(p) ** n + np.cos(p - h) ** n) / h**2
    assert np.all(np.abs(fd) < 1e-4 * n)
    assert ls.n_where_limit_is_inflexion() == pytest.approx(23.40, abs=5e-3)
    lim = np.arccos(lobes.epicentre_limit_cos(n))
    rel = lim / p - 1
    assert rel.min() == pytest.approx(-0.00510, abs=5e-5)
    assert rel.max() == pytest.approx(0.01069, abs=5e-5)
    assert float(ls.k_at_inflexion(1e6)) == pytest.approx(0.5, abs=1e-6)


def test_render_summary_is_short_and_does_bounded_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Short, and cheap enough for ``make demo``: a fixed budget of quadratures (the
    three eq 12 evaluations, four integrals each), bounded 1-D searches (one per peak)
    and one root find — counted, not timed, so a busy machine cannot fail it."""
    calls: dict[str, int] = {}

    def counting(module: object, name: str) -> None:
        real = getattr(module, name)

        def counted(*args: object, **kwargs: object) -> object:
            calls[name] = calls.get(name, 0) + 1
            return real(*args, **kwargs)

        monkeypatch.setattr(module, name, counted)

    counting(ls.integrate, "quad")
    counting(ls.optimize, "minimize_scalar")
    counting(ls.optimize, "brentq")
    text = ls.render_summary()
    assert calls["quad"] <= 12
    assert calls["minimize_scalar"] <= 12
    assert calls["brentq"] <= 1
    lines = text.splitlines()
    assert len(lines) <= 25
    assert max(len(x) for x in lines) <= 100
    for figure in ("0.46254", "0.46255", "1.90%", "2.84%", "1.55%", "7.59%", "10.31%", "0.45106"):
        assert figure in text
