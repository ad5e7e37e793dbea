"""Microfacet distributions and Smith terms; the Cook-Torrance models built on them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.brdf import microfacet as mf
from gonio.brdf.quadrature import hemisphere_integral

ALPHAS = [0.05, 0.3, 1.0]


def _dir(theta: float, phi: float = 0.0) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _xyz(w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return w[..., 0], w[..., 1], w[..., 2]


@pytest.mark.parametrize("alpha", ALPHAS)
def test_isotropic_distributions_are_normalized(alpha):
    for d in (mf.ggx_d, mf.beckmann_d):
        total = hemisphere_integral(lambda w, d=d: d(*_xyz(w), alpha) * w[..., 2])
        assert total == pytest.approx(1.0, abs=1e-7)


@pytest.mark.parametrize(("ax", "ay"), [(0.05, 0.3), (0.3, 0.05), (0.2, 1.0)])
def test_anisotropic_ggx_is_normalized(ax, ay):
    # elongated in φ: refine the φ rule accordingly
    total = hemisphere_integral(lambda w: mf.ggx_aniso_d(*_xyz(w), ax, ay) * w[..., 2], n_phi=1024)
    assert total == pytest.approx(1.0, abs=1e-7)


def test_d_is_scale_invariant_and_peaks_at_the_normal():
    h = np.array([0.1, -0.2, 0.9])
    for d in (mf.ggx_d, mf.beckmann_d):
        for scale in (1e-60, 1e60):
            assert d(*(scale * h), 0.3) == pytest.approx(d(*h, 0.3), rel=1e-14)
        assert d(0.0, 0.0, 1.0, 0.3) == pytest.approx(1 / (np.pi * 0.09), rel=1e-14)
    assert mf.ggx_d(0.0, 0.0, 0.0, 0.3) == 0.0
    assert mf.beckmann_d(0.0, 0.0, 0.0, 0.3) == 0.0
    assert mf.beckmann_d(1.0, 0.0, 0.0, 0.3) == 0.0
    assert mf.ggx_d(1.0, 0.0, 0.0, 0.3) == pytest.approx(0.09 / np.pi)


@pytest.mark.parametrize("theta", [0.3, 1.0, 1.4, 1.55])
@pytest.mark.parametrize("alpha", [0.1, 0.5])
@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_smith_lambda_satisfies_the_projected_area_identity(dist, alpha, theta):
    """∫ max(0, w·m) D(m) dωm = cos θ (1 + Λ(w)) (Heitz 2014): checks Λ against D."""
    d, lam = {"ggx": (mf.ggx_d, mf.ggx_lambda), "beckmann": (mf.beckmann_d, mf.beckmann_lambda)}[
        dist
    ]
    w = _dir(theta, 0.4)
    lhs = hemisphere_integral(
        lambda m: d(*_xyz(m), alpha) * np.maximum(m @ w, 0.0), n_phi=2048, order=24
    )
    rhs = w[2] * (1.0 + lam(*w, alpha))
    assert lhs == pytest.approx(rhs, rel=2e-5)


unit_dir = st.tuples(st.floats(1e-6, 1.5), st.floats(0.0, 2 * np.pi))


@settings(max_examples=100)
@given(a=unit_dir, b=unit_dir, alpha=st.floats(0.01, 2.0))
def test_visibility_equals_g2_over_the_cosines(a, b, alpha):
    wi, wo = _dir(*a), _dir(*b)
    for lam, bfun in ((mf.ggx_lambda, mf.ggx_b), (mf.beckmann_lambda, mf.beckmann_b)):
        g2 = 1.0 / (1.0 + lam(*wi, alpha) + lam(*wo, alpha))
        v = mf.visibility(bfun(*wi, alpha), bfun(*wo, alpha), wi[2], wo[2])
        assert v == pytest.approx(g2 / (4 * wi[2] * wo[2]), rel=1e-11)


def test_b_at_the_normal_and_the_horizon():
    for alpha in (0.05, 0.7):
        assert mf.ggx_b(0.0, 0.0, 1.0, alpha) == 0.5
        assert mf.beckmann_b(0.0, 0.0, 1.0, alpha) == 0.5
        assert mf.ggx_b(1.0, 0.0, 0.0, alpha) == pytest.approx(alpha / 2)
        assert mf.beckmann_b(1.0, 0.0, 0.0, alpha) == pytest.approx(alpha / (2 * np.sqrt(np.pi)))


def _pairs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


@pytest.mark.parametrize("alpha", [0.02, 0.1, 0.5, 1.3])
@pytest.mark.parametrize(
    "fresnel",
    [{"fresnel": "none"}, {"fresnel": "conductor", "ior": (0.2, 0.4, 1.4), "k": (3.4, 2.4, 1.8)}],
)
def test_anisotropic_ggx_reduces_to_isotropic(alpha, fresnel):
    wi, wo = _pairs(20000, 5)
    iso = brdf.create("cook_torrance", alpha=alpha, distribution="ggx", **fresnel).eval(wi, wo)
    aniso = brdf.create("ggx_anisotropic", alpha_x=alpha, alpha_y=alpha, **fresnel).eval(wi, wo)
    np.testing.assert_allclose(aniso, iso, rtol=1e-12, atol=0.0)


def test_anisotropic_ggx_stretches_along_its_rough_axis():
    model = brdf.create("ggx_anisotropic", alpha_x=0.4, alpha_y=0.05, fresnel="none")
    wi = _dir(0.0)
    along_x, along_y = model.eval(wi, _dir(0.3, 0.0)), model.eval(wi, _dir(0.3, np.pi / 2))
    assert along_x > 50 * along_y


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_cook_torrance_closed_form_at_normal_incidence(dist):
    alpha, f0 = 0.2, 0.04
    model = brdf.create("cook_torrance", alpha=alpha, distribution=dist, f0=f0)
    n = _dir(0.0)
    # h = n, θd = 0, Λ = 0: f = D(0) F0 / 4 = F0 / (4 π α²)
    assert model.eval(n, n) == pytest.approx(f0 / (4 * np.pi * alpha**2), rel=1e-14)


@pytest.mark.parametrize("dist", ["ggx", "beckmann"])
def test_grazing_is_zero_and_the_limit_is_finite(dist):
    model = brdf.create("cook_torrance", alpha=0.3, distribution=dist, fresnel="none")
    wo = _dir(0.4, np.pi)
    grazing = np.array([1.0, 0.0, 0.0])
    assert model.eval(grazing, wo) == 0.0
    assert model.eval(wo, grazing) == 0.0
    assert model.eval(grazing, grazing) == 0.0
    # f tends to D F / (4 cos θo B(θ = 90°)) as θi → 90°: finite, non-zero; f cos θi → 0
    eps = np.array([1e-4, 1e-8, 1e-12])
    wi = np.stack([np.sqrt(1 - eps**2), np.zeros(3), eps], -1)
    f = model.eval(wi, wo)
    assert np.all(np.isfinite(f)) and np.all(f > 0)
    assert f[2] == pytest.approx(f[1], rel=1e-6)
    # both directions approaching the horizon: f grows like 1 / cos θ, f cos θ stays finite
    both = model.eval(wi, wi * [-1, 1, 1])
    assert np.all(np.isfinite(both))
    np.testing.assert_allclose(both * eps, (both * eps)[-1], rtol=1e-3)
