"""Hemispherical integrals that resolve sharp lobes: D normalization, directional albedo.

Both integrate in polar coordinates (θ, φ) about the normal: composite
Gauss-Legendre in θ on panels dyadic toward both ends of the θ range
([0, 2⁻ᴸ], …, [¼, ½], [½, ¾], …, [1 − 2⁻ᴸ, 1]), which resolves a peak at θ = 0 and a
boundary layer at the end of the range down to widths ~2⁻ᴸ; the trapezoidal rule
in φ (spectrally accurate for smooth periodic integrands).

Directional albedo a(wi) = ∫ f(wi, wo) cos θo dωo is computed in the halfway
domain: wo = 2 (wi · h) h − wi, dωo = 4 (wi · h) dωh. Every lobe here (Phong's
mirror direction, Blinn's and the microfacet models' h = n) peaks at θh = 0, the
pole of the grid. The horizon cos θo = 0 is a coordinate line: for wi at
(θi, φi), cos θo = R cos(2θh − γ) with γ = atan2(sin θi cos(φh − φi), cos θi), so
the visible range is θh ∈ [0, (π/2 + γ)/2] and the integrand (∝ cos θo) vanishes
smoothly there; masking makes a boundary layer of width ~cos θi at that end at
grazing incidence, which the dyadic panels resolve. Near θi = 90°, γ varies over a
φ-range ~cot θi, so the default φ count grows as 1/cos θi.

Accuracy, measured (tests/gonio/brdf/test_quadrature.py): Lambert albedo to 1e-12
for θi up to 89.9°; Phong (n = 1000), Blinn-Phong (n = 1000), GGX and Beckmann
(α = 0.05) and anisotropic GGX (0.05, 0.3) albedos change by < 1e-9 when both
rules are refined. Lobes with a kink (the cut cosine-quadratic) converge to ~1e-6.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np

from gonio.brdf.base import BRDF
from gonio.types import ArrayLike, FloatArray

_CHUNK = 32768


@functools.cache
def legendre(n: int) -> tuple[FloatArray, FloatArray]:
    """The ``n``-point Gauss-Legendre nodes and weights on [−1, 1] (numpy's
    ``leggauss``, an eigenvalue problem of size n), computed once per n: read-only."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def radial_rule(order: int = 16, levels: int = 16) -> tuple[FloatArray, FloatArray]:
    """Nodes t ∈ (0, 1) and weights of the composite Gauss-Legendre rule on [0, 1].

    Panels are dyadic toward both ends: [0, 2⁻ᴸ], …, [¼, ½], [½, ¾], …, [1 − 2⁻ᴸ, 1].
    """
    x, w = legendre(order)
    low = 2.0 ** -np.arange(levels, 0, -1, dtype=np.float64)  # 2⁻ᴸ … ½
    edges = np.concatenate([[0.0], low, 1.0 - low[-2::-1], [1.0]])
    a, b = edges[:-1, None], edges[1:, None]
    nodes = ((a + b) / 2 + (b - a) / 2 * x).ravel()
    return np.asarray(nodes, dtype=np.float64), np.asarray(((b - a) / 2 * w).ravel(), np.float64)


def periodic_rule(n: int) -> tuple[FloatArray, FloatArray]:
    """n equispaced nodes on [0, 2π) (offset by half a step) and their equal weights."""
    nodes = (np.arange(n, dtype=np.float64) + 0.5) * (2.0 * np.pi / n)
    return nodes, np.full(n, 2.0 * np.pi / n, dtype=np.float64)


def _polar(theta: FloatArray, phi: FloatArray) -> FloatArray:
    s = np.sin(theta)
    return np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), np.cos(theta)), -1)


def hemisphere_integral(
    func: Callable[[FloatArray], FloatArray],
    *,
    n_phi: int = 256,
    order: int = 16,
    levels: int = 16,
) -> FloatArray:
    """∫ func(w) dω over the upper hemisphere; ``func`` maps (..., 3) to (...) or (..., k)."""
    t, wt = radial_rule(order, levels)
    phi, wp = periodic_rule(n_phi)
    theta = (np.pi / 2) * t[:, None]
    values = func(_polar(theta, phi[None, :]))
    weight = (np.pi / 2) * wt[:, None] * np.sin(theta) * wp[None, :]
    return np.asarray(np.tensordot(weight, values, axes=([0, 1], [0, 1])), dtype=np.float64)


def default_n_phi(theta_i: float) -> int:
    """φ nodes for the albedo at θi: 256, growing as 16/cos θi past 86.4° (≤ 16384)."""
    c = max(float(np.cos(theta_i)), 2.0 / 2048.0)
    return int(max(256, 8 * np.ceil(2.0 / c)))


def directional_albedo(
    model: BRDF,
    theta_i: ArrayLike,
    phi_i: float = 0.0,
    *,
    n_phi: int | None = None,
    order: int = 16,
    levels: int = 16,
) -> FloatArray:
    """a(θi) = ∫ f(wi, wo) cos θo dωo for wi at (θi, φi); shape of θi, plus (3,) if RGB.

    θi ∈ [0, π/2) in radians (a Python loop runs over the θi values, not samples).
    """
    thetas = np.asarray(theta_i, dtype=np.float64)
    t, wt = radial_rule(order, levels)
    out: list[FloatArray] = []
    for ti in thetas.ravel():
        phi, wp = periodic_rule(default_n_phi(ti) if n_phi is None else n_phi)
        gamma = np.arctan2(np.sin(ti) * np.cos(phi), np.cos(ti))
        tmax = 0.5 * (np.pi / 2 + gamma)  # visible θh range, per φh relative to φi
        wi = np.array([np.sin(ti) * np.cos(phi_i), np.sin(ti) * np.sin(phi_i), np.cos(ti)])
        total = np.zeros((3,) if model.is_rgb else ())
        rows = max(1, _CHUNK // phi.size)  # blocks of ~_CHUNK points stay in cache
        for k in range(0, t.size, rows):
            th = t[k : k + rows, None] * tmax[None, :]
            h = _polar(th, phi[None, :] + phi_i)
            d = h @ wi
            wo = 2.0 * d[..., None] * h - wi
            jac = np.maximum(wo[..., 2], 0.0) * 4.0 * d * np.sin(th) * tmax[None, :]
            weight = jac * wt[k : k + rows, None] * wp[None, :]
            total = total + np.tensordot(weight, model.eval(wi, wo), axes=([0, 1], [0, 1]))
        out.append(np.asarray(total, dtype=np.float64))
    shape = thetas.shape + ((3,) if model.is_rgb else ())
    return np.asarray(np.reshape(out, shape), dtype=np.float64)
