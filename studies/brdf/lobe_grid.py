"""Grid checks of the lobes' errors (`gonio.brdf.lobe_errors`): maxima over ψ by
a grid and zoom-ins, which check the exact epicentre maxima and give the absolute
errors over the hemisphere, and the angle of the cosine-quadratic lobe's zero.

Conventions as in `gonio.brdf.lobe_errors`: c = cos ψ, n the shininess, F_B = cos^n ψ,
δ = |F − F_B| / F_B, Δ = |F − F_B|; angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from gonio.brdf import K_PRINTED, Lobe, lobes
from gonio.types import ArrayLike, FloatArray


def grid_max(
    fun: Callable[[FloatArray, FloatArray], FloatArray],
    n: ArrayLike,
    lo: ArrayLike,
    hi: ArrayLike,
    points: int = 4097,
    rounds: int = 3,
    sub: int = 33,
    power: float = 1.0,
) -> tuple[FloatArray, FloatArray]:
    """Max over ψ ∈ [lo, hi] of ``fun(ψ, n)`` per n, and its ψ: a grid then zoom-ins.

    The grid is lo + (hi − lo) s^power, s uniform (power 2 crowds points near lo);
    each round regrids the two cells around the best point with ``sub`` points, so
    the final cell is (hi − lo)/(points − 1) · (2/(sub − 1))^rounds wide (≈ 6e-8 of
    the span, ψ to that; the max value, second order, to ~1e-15) for a smooth max.
    """
    nn = np.asarray(n, dtype=np.float64).reshape(-1, 1)
    a = np.broadcast_to(np.asarray(lo, dtype=np.float64).reshape(-1, 1), nn.shape)
    b = np.broadcast_to(np.asarray(hi, dtype=np.float64).reshape(-1, 1), nn.shape)
    psi = a + (b - a) * np.linspace(0.0, 1.0, points) ** power
    rows = np.arange(nn.shape[0])
    for r in range(rounds + 1):
        v = fun(psi, nn)
        i = np.argmax(v, axis=1)
        if r == rounds:
            break
        left = psi[rows, np.maximum(i - 1, 0)]
        right = psi[rows, np.minimum(i + 1, psi.shape[1] - 1)]
        psi = left[:, None] + (right - left)[:, None] * np.linspace(0.0, 1.0, sub)
    return v[rows, i], psi[rows, i]


def epicentre_grid_relative_error(
    lobe: Lobe, n: ArrayLike, k: float = K_PRINTED
) -> tuple[FloatArray, FloatArray]:
    """Max δ over the epicentre zone by :func:`grid_max` (check of the exact version)."""
    nn = np.asarray(n, dtype=np.float64)
    lim = np.arccos(np.exp(-k / nn))

    def delta(psi: FloatArray, m: FloatArray) -> FloatArray:
        c = np.cos(psi)
        return np.abs(lobe(c, m) / lobes.power_cosine(c, m) - 1.0)

    return grid_max(delta, nn, 0.0, lim)


def max_abs_error(lobe: Lobe, n: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Max Δ = |F − F_B| over ψ ∈ [0, π/2] per n, and the ψ where it occurs."""

    def delta(psi: FloatArray, m: FloatArray) -> FloatArray:
        c = np.cos(psi)
        return np.abs(lobe(c, m) - lobes.power_cosine(c, m))

    return grid_max(delta, n, 0.0, math.pi / 2.0, power=2.0)


def zero_crossing_psi(n: ArrayLike, xi: float) -> FloatArray:
    """ψ where (ξ n (cos ψ − 1) + 1)² first reaches 0: acos(1 − 1/(ξ n))."""
    return np.asarray(np.arccos(lobes.zero_crossing_cos(n, xi)), dtype=np.float64)
