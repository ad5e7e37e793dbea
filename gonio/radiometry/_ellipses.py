"""Centred conics in the sample plane: quadratic forms q(u) = uᵀMu, their crossings and
exact sector integrals ∫ dβ / q(u(β)), vectorized over leading axes.

A form is (A, B, C, det) for M = [[A, C], [C, B]] with det = AB − C² passed in (the
callers know it in closed form, free of cancellation). A centred region {x : xᵀMx ≤ 1}
has radial extent r(β) = q(u(β))^(−1/2) along u(β) = (cos β, sin β); the intersection
of centred convex regions has r² = min over the regions, and its area is
½ ∫₀^{2π} r² dβ.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gonio.types import FloatArray


def azimuth(w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(cos φ, sin φ) of w's azimuth, (1, 0) where it is undefined (w = ±z)."""
    rho = np.hypot(w[..., 0], w[..., 1])
    safe = np.where(rho > 0.0, rho, 1.0)
    return (
        np.asarray(np.where(rho > 0.0, w[..., 0] / safe, 1.0), dtype=np.float64),
        np.asarray(np.where(rho > 0.0, w[..., 1] / safe, 0.0), dtype=np.float64),
    )


class Form(NamedTuple):
    """M = [[a, c], [c, b]] with determinant ``det`` (> 0 or ≥ 0, see users)."""

    a: FloatArray
    b: FloatArray
    c: FloatArray
    det: FloatArray


def ellipse_form(
    semi_along: FloatArray, semi_across: FloatArray, cos_az: FloatArray, sin_az: FloatArray
) -> Form:
    """The form of an ellipse with inverse semi-axes ``semi_along`` = 1/a along the unit
    azimuth (cos_az, sin_az) and ``semi_across`` = 1/b across it (given as inverses so a
    degenerate strip, 1/a = 0, is representable)."""
    ka2, kb2 = semi_along**2, semi_across**2
    return Form(
        ka2 * cos_az**2 + kb2 * sin_az**2,
        ka2 * sin_az**2 + kb2 * cos_az**2,
        (ka2 - kb2) * cos_az * sin_az,
        (semi_along * semi_across) ** 2,
    )


def quadratic(m: Form, cos_b: FloatArray, sin_b: FloatArray) -> FloatArray:
    """q(u) = uᵀMu at u = (cos β, sin β)."""
    return np.asarray(
        m.a * cos_b * cos_b + 2.0 * m.c * cos_b * sin_b + m.b * sin_b * sin_b, dtype=np.float64
    )


def crossings(m: Form, n: Form) -> tuple[FloatArray, FloatArray]:
    """Two angles in [0, π) where q_m = q_n, when the two conics cross (otherwise two
    harmless extra angles). From the eigen-decomposition of M − N: uᵀ(M − N)u =
    λ₁ cos²δ + λ₂ sin²δ, δ = β − β₁, which vanishes at tan δ = ±√(λ₁ / −λ₂).

    The small eigenvalue is det(M − N) / (the large one), with det(M − N) expanded
    through the closed-form determinants: near grazing the forms' entries span 30
    orders of magnitude and mean ± radius would cancel.
    """
    p, s, r = m.a - n.a, m.b - n.b, m.c - n.c
    mean, rad = 0.5 * (p + s), np.hypot(0.5 * (p - s), r)
    det = m.det + n.det - (m.a * n.b + n.a * m.b - 2.0 * m.c * n.c)
    big = np.where(mean >= 0.0, mean + rad, mean - rad)
    small = det / np.where(big != 0.0, big, 1.0)
    lam1 = np.where(mean >= 0.0, big, small)
    lam2 = np.where(mean >= 0.0, small, big)
    beta1 = 0.5 * np.arctan2(2.0 * r, p - s)
    delta = np.arctan2(np.sqrt(np.maximum(lam1, 0.0)), np.sqrt(np.maximum(-lam2, 0.0)))
    return np.mod(beta1 + delta, np.pi), np.mod(beta1 - delta, np.pi)


def sector(m: Form, beta_a: FloatArray, beta_b: FloatArray) -> FloatArray:
    """∫ from β_a to β_b of dβ / q(u(β)) for 0 ≤ β_b − β_a ≤ π/2 and M positive definite:
    the area of the sector of {uᵀMu ≤ 1} between the two rays, times 2. Mapping by L
    with LᵀL = M turns the ellipse into the unit disc (areas × √det) and the rays into
    rays at angle atan2(√det · sin Δβ, u_aᵀ M u_b) apart."""
    ca, sa, cb, sb = np.cos(beta_a), np.sin(beta_a), np.cos(beta_b), np.sin(beta_b)
    p = m.a * ca * cb + m.c * (ca * sb + sa * cb) + m.b * sa * sb
    root = np.sqrt(m.det)
    return np.asarray(np.arctan2(root * np.sin(beta_b - beta_a), p) / root, dtype=np.float64)
