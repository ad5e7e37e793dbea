"""Microfacet distributions D and Smith masking terms, in Cartesian components.

D(m) is normalized so that ∫ D(m) cos θm dωm = 1 over the hemisphere. Every D
takes the components of a halfway vector of any length in [1e-60, 1e60] (only its
direction matters; `Pair.halfway` scales its largest component to ±1) and uses
tan² θm = (x² + y²)/z², which keeps full relative precision near the peak (no
1 − cos θ cancellation):

    GGX (Trowbridge–Reitz):  D = 1 / (π α² cos⁴θ (1 + tan²θ / α²)²)
    anisotropic GGX:         D = 1 / (π αx αy ‖(x/αx, y/αy, z)‖⁴)    (unit m)
    Beckmann:                D = exp(−tan²θ / α²) / (π α² cos⁴θ)

Smith's Λ for a unit direction (x, y, z), a = z / (α sin θ):

    GGX:       Λ = (−1 + √(1 + α² tan²θ)) / 2,   anisotropic: α² tan²θ → (αx² x² + αy² y²)/z²
    Beckmann:  Λ = (erf(a) − 1) / 2 + exp(−a²) / (2 a √π)          (exact form)

The height-correlated masking-shadowing G2 = 1 / (1 + Λ(wi) + Λ(wo)) (Heitz 2014)
enters the BRDF only through the visibility V = G2 / (4 cos θi cos θo). Writing
B(w) = cos θ (½ + Λ(w)) gives V = 1 / (4 (cos θo B(wi) + cos θi B(wo))) with

    GGX:       B = ½ √(z² + α² (x² + y²))
    Beckmann:  B = ½ z erf(a) + α sin θ exp(−a²) / (2 √π),

both finite and positive at z = 0 (B = α/2 and α/(2√π)); V is finite unless both
directions are exactly grazing. The models set f = 0 when either is exactly grazing.
"""

from __future__ import annotations

import numpy as np
from scipy.special import erf

from gonio.types import FloatArray

_SQRT_PI = float(np.sqrt(np.pi))
_TINY = 1e-300
#: Beyond this tan²θ/α² the Beckmann exponential is 0 in float64.
_BECKMANN_CUT = 1e4


def ggx_d(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """Isotropic GGX D of the direction (x, y, z), in sr⁻¹; 0 for the zero vector."""
    r2, z2 = x * x + y * y, z * z
    a2 = alpha * alpha
    den = a2 * z2 + r2  # = ‖m‖² cos²θ (α² + tan²θ)
    num = a2 * (r2 + z2) ** 2
    return np.asarray(num / (np.pi * np.maximum(den * den, _TINY)), dtype=np.float64)


def ggx_aniso_d(
    x: FloatArray, y: FloatArray, z: FloatArray, alpha_x: float, alpha_y: float
) -> FloatArray:
    """Anisotropic GGX D (roughness αx along the sample's x axis), in sr⁻¹."""
    q = (x / alpha_x) ** 2 + (y / alpha_y) ** 2 + z * z
    n2 = x * x + y * y + z * z
    return np.asarray(
        n2 * n2 / (np.pi * alpha_x * alpha_y * np.maximum(q * q, _TINY)), dtype=np.float64
    )


def beckmann_d(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """Isotropic Beckmann D of the direction (x, y, z), in sr⁻¹; 0 where z ≤ 0."""
    a2 = alpha * alpha
    den = a2 * z * z
    t = np.minimum((x * x + y * y) / np.maximum(den, _TINY), _BECKMANN_CUT)  # tan²θ / α²
    t = np.where(den > 0.0, t, _BECKMANN_CUT)
    # 1 / cos⁴θ = (1 + tan²θ)²
    return np.asarray(np.exp(-t) * (1.0 + a2 * t) ** 2 / (np.pi * a2), dtype=np.float64)


def ggx_lambda(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """Smith Λ of GGX for a unit direction with z > 0."""
    return np.asarray(
        0.5 * (np.sqrt(1.0 + alpha * alpha * (x * x + y * y) / (z * z)) - 1.0), dtype=np.float64
    )


def beckmann_lambda(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """Smith Λ of Beckmann for a unit direction with 0 < z < 1."""
    a = z / (alpha * np.sqrt(x * x + y * y))
    return np.asarray(
        0.5 * (erf(a) - 1.0) + np.exp(-a * a) / (2.0 * a * _SQRT_PI), dtype=np.float64
    )


def ggx_b(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """B = cos θ (½ + Λ) of isotropic GGX, for a unit direction with z ≥ 0."""
    return np.asarray(0.5 * np.sqrt(z * z + alpha * alpha * (x * x + y * y)), dtype=np.float64)


def ggx_aniso_b(
    x: FloatArray, y: FloatArray, z: FloatArray, alpha_x: float, alpha_y: float
) -> FloatArray:
    """B = cos θ (½ + Λ) of anisotropic GGX, for a unit direction with z ≥ 0."""
    q = z * z + (alpha_x * x) ** 2 + (alpha_y * y) ** 2
    return np.asarray(0.5 * np.sqrt(q), dtype=np.float64)


def beckmann_b(x: FloatArray, y: FloatArray, z: FloatArray, alpha: float) -> FloatArray:
    """B = cos θ (½ + Λ) of Beckmann, for a unit direction with z ≥ 0."""
    s = np.sqrt(x * x + y * y)
    den = alpha * s
    # a = z / (α sin θ); past 1e12 erf(a) = 1 and exp(−a²) = 0 in float64.
    a = z / np.maximum(den, np.maximum(1e-12 * z, _TINY))
    return np.asarray(0.5 * z * erf(a) + den * np.exp(-a * a) / (2.0 * _SQRT_PI), dtype=np.float64)


def visibility(bi: FloatArray, bo: FloatArray, ci: FloatArray, co: FloatArray) -> FloatArray:
    """V = G2 / (4 cos θi cos θo) from B(wi), B(wo) and the clamped cosines, in [0, ∞).

    0 where either cosine is 0 (the horizon is masked). The denominator is floored at
    1e-290, which only matters when both cosines are below ~1e-289 / α.
    """
    den = np.maximum(co * bi + ci * bo, 1e-290)
    grazing = (ci <= 0.0) | (co <= 0.0)
    return np.where(grazing, 0.0, 0.25 / np.where(grazing, 1.0, den))
