"""Specular lobe shapes as plain functions of cos ψ and the shininess n, after
Romanyuk et al., *Modified cosine-quadratic reflectance model*.

ψ is whatever angle the caller's model uses: between the mirror direction and the
view direction (Phong) or between the normal and the halfway vector (Blinn). Every
function is vectorized over broadcastable ``cos_psi`` and ``n`` and returns float64;
``cos_psi`` below 0 yields 0 (the lobe does not reach below the horizon of ψ).

The names follow Romanyuk et al.: F_B = cos^n ψ (the reference), F_2 the cosine-quadratic
lobe with ξ = 1/2, F_VOL the modified one with ξ from its equation 12 (or 29/64),
F_S Schlick's rational approximation.
"""

from __future__ import annotations

import numpy as np

from gonio.types import ArrayLike, FloatArray

XI_STANDARD = 0.5
XI_29_64 = 29.0 / 64.0


def xi_equation_12() -> float:
    """ξ solving Romanyuk et al.'s equation 12, 1.098 = −0.71068 ξ + 0.12026 ξ² + 1.40119.

    Of the two roots (≈ 0.4629 and ≈ 5.447) the one in (0, 1) is the lobe's; the
    paper rounds it to 0.463.
    """
    a, b, c = 0.12026, -0.71068, 1.40119 - 1.098
    return float((-b - np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a))


def power_cosine(cos_psi: ArrayLike, n: ArrayLike) -> FloatArray:
    """F_B = cos^n ψ, the Phong / Blinn lobe (0 where cos ψ < 0, even for n = 0)."""
    raw = np.asarray(cos_psi, dtype=np.float64)
    nn = np.asarray(n, dtype=np.float64)
    value = np.power(np.maximum(raw, 0.0), nn)
    if np.any(nn == 0.0):  # 0⁰ = 1 would leave the lobe at 1 behind the horizon of ψ
        value = np.where(raw < 0.0, 0.0, value)
    return np.asarray(value, dtype=np.float64)


def cosine_quadratic(
    cos_psi: ArrayLike, n: ArrayLike, xi: ArrayLike = XI_STANDARD, cut: bool = True
) -> FloatArray:
    """(ξ n (cos ψ − 1) + 1)², Romanyuk et al. eq. 3 (ξ = 1/2 is F_2, ξ ≈ 0.463 is F_VOL).

    The parabola reaches 0 at cos ψ = 1 − 1/(ξ n) and rises again beyond it; with
    ``cut`` (the default) it is zeroed from that point on, as the paper prescribes
    for F_VOL. ``cut=False`` gives the raw polynomial for the paper's comparisons.
    """
    c = np.asarray(cos_psi, dtype=np.float64)
    xn = np.asarray(xi, dtype=np.float64) * np.asarray(n, dtype=np.float64)
    t = xn * (c - 1.0) + 1.0
    if cut:
        t = np.maximum(t, 0.0)
        if np.all(xn >= 1.0):  # then t < 0, cut to 0, wherever cos ψ < 0
            return np.asarray(t * t, dtype=np.float64)
    return np.asarray(np.where(c < 0.0, 0.0, t * t), dtype=np.float64)


def zero_crossing_cos(n: ArrayLike, xi: ArrayLike = XI_29_64) -> FloatArray:
    """cos ψ at which the cosine-quadratic lobe reaches 0: 1 − 1/(ξ n).

    For ξ = 29/64 this is Romanyuk et al.'s eq. 14, (29 n − 64)/(29 n).
    """
    xn = np.asarray(xi, dtype=np.float64) * np.asarray(n, dtype=np.float64)
    return np.asarray(1.0 - 1.0 / xn, dtype=np.float64)


def schlick(cos_psi: ArrayLike, n: ArrayLike) -> FloatArray:
    """F_S = cos ψ / (n − n cos ψ + cos ψ), Schlick's approximation (Romanyuk et al. eq. 4).

    0 where cos ψ < 0; the 0/0 at cos ψ = 0 with n = 0 is taken as its limit 1 = cos⁰ψ.
    """
    raw = np.asarray(cos_psi, dtype=np.float64)
    c = np.maximum(raw, 0.0)
    nn = np.asarray(n, dtype=np.float64)
    if not np.any(nn == 0.0):  # n > 0: the denominator is ≥ min(n, 1) > 0
        return np.asarray(c / (nn - nn * c + c), dtype=np.float64)
    den = nn - nn * c + c
    value = np.where(den > 0.0, c / np.where(den > 0.0, den, 1.0), 1.0)
    return np.asarray(np.where(raw < 0.0, 0.0, value), dtype=np.float64)


def epicentre_limit_cos(n: ArrayLike) -> FloatArray:
    """cos ψ at the edge of the glare's epicentre zone, exp(−0.511 / n) (Romanyuk et al.)."""
    return np.asarray(np.exp(-0.511 / np.asarray(n, dtype=np.float64)), dtype=np.float64)
