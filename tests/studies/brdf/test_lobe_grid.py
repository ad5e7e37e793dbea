"""studies.brdf.lobe_grid: the lobe study's maxima by grids, against the exact ones and
dense grids (Romanyuk et al.'s modified cosine-quadratic model)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.brdf import lobe_errors as ls
from gonio.brdf import lobes
from studies.brdf import lobe_grid as lg

LOBES = {lb.name: lb for lb in ls.study_lobes()}


@pytest.mark.parametrize("name", list(LOBES))
def test_exact_epicentre_max_matches_grid(name: str) -> None:
    n = np.geomspace(16.0, 1000.0, 33)
    exact, c = ls.epicentre_max_relative_error(LOBES[name], n)
    grid, psi = lg.epicentre_grid_relative_error(LOBES[name], n)
    np.testing.assert_allclose(grid, exact, rtol=1e-12)
    np.testing.assert_allclose(psi, np.arccos(c), atol=1e-6)


@pytest.mark.parametrize("k", [0.2, ls.K_LN_5_3, 0.9])
def test_exact_epicentre_max_follows_the_zone_constant(k: float) -> None:
    n = np.geomspace(16.0, 1000.0, 9)
    for lobe in LOBES.values():
        exact = ls.epicentre_max_relative_error(lobe, n, k)[0]
        np.testing.assert_allclose(exact, lg.epicentre_grid_relative_error(lobe, n, k)[0], 1e-12)


# name: max Δ over ψ ∈ [0, π/2] and n ∈ [16, 1000] (at n = 1000), 4 decimals.
ABSOLUTE = {
    "F_VOL(0.463)": 0.1375,
    "F_VOL(eq12)": 0.1372,
    "F_VOL(29/64)": 0.1310,
    "F_2": 0.1616,
    "F_S": 0.2034,
}


@pytest.mark.parametrize("name", list(ABSOLUTE))
def test_absolute_error_maxima_are_in_the_attenuation_zone(name: str) -> None:
    lobe = LOBES[name]
    n = np.array([16.0, 100.0, 1000.0])
    d, psi = lg.max_abs_error(lobe, n)
    assert float(d[-1]) == pytest.approx(ABSOLUTE[name], abs=5e-5)
    assert np.all(psi > 1.7 * np.arccos(lobes.epicentre_limit_cos(n)))
    for i, m in enumerate(n):  # against a plain dense grid in ψ
        p = np.linspace(0.0, math.pi / 2, 2_000_001)
        brute = np.max(np.abs(lobe(np.cos(p), m) - lobes.power_cosine(np.cos(p), m)))
        assert float(d[i]) == pytest.approx(brute, abs=1e-9)
        assert float(d[i]) >= brute - 1e-15


def test_grid_max_and_max_over_n_on_known_functions() -> None:
    v, x = lg.grid_max(lambda p, n: -((p - 0.3 / n) ** 2), [1.0, 2.0, 3.0], 0.0, 1.0)
    step = (1 / 4096) * (2 / 32) ** 3  # final cell with the default points, sub, rounds
    np.testing.assert_allclose(x, [0.3, 0.15, 0.1], atol=step)
    np.testing.assert_allclose(v, 0.0, atol=step**2)
    peak, at = ls.max_over_n(lambda n: -((np.log(n) - math.log(123.4)) ** 2))
    assert at == pytest.approx(123.4, rel=1e-6)
    assert peak == pytest.approx(0.0, abs=1e-12)
