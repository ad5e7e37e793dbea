"""Angular integration over the detector's aperture.

The detector collects the cap of solid angle Ω around wo (half-angle α with
Ω = 2π(1 − cos α)), so it measures

    A(wi, wo) = ∫_cap f(wi, ω) · w(ω) dω,    w = cos θ_ω (collimated) or 1 (point source),

instead of f(wi, wo) · w(wo) · Ω; the simulator then uses Φ = K · A. Directions of the
cap below the horizon contribute 0. As Ω → 0, A / Ω → f(wi, wo) · w(wo).

Quadrature: a tensor rule in the cap's polar coordinates about wo, Gauss-Legendre in
cos ψ on [cos α, 1] (``order[0]`` nodes) × the periodic trapezoid in the azimuth about
wo (``order[1]`` nodes); on a ring that dips below the horizon, Gauss-Legendre over its
visible arc instead. Default (12, 24): 288 BRDF evaluations per pair.

Accuracy of the default rule (measured against (96, 192), docs/explanations/radiometry.md): GGX
α = 0.02 around its peak, ≤ 1e-14 relative at Ω ≤ 1e-3 sr, 3e-10 at 3e-3 sr, 3.4e-6 at
1e-2 sr; a cap cut by the horizon (grazing wo), weight "one" to rounding, weight "cos"
to 1e-4 (the cos weight has a √ endpoint singularity in cos ψ there).
"""

from __future__ import annotations

import math
from typing import Literal, TypeAlias

import numpy as np

from gonio.brdf import legendre
from gonio.errors import DomainError
from gonio.radiometry._checks import direction_pair, positive
from gonio.radiometry.ideal import Source, source_kind
from gonio.types import ArrayLike, BrdfEval, FloatArray

Weight: TypeAlias = Literal["cos", "one"]

#: Default quadrature order: (Gauss-Legendre nodes in cos ψ, trapezoid nodes in azimuth).
DEFAULT_ORDER = (12, 24)
_BLOCK = 1 << 17


def weight_for(source: Source) -> Weight:
    """The aperture weight of a source type: "cos" (collimated) or "one" (point)."""
    return "cos" if source_kind(source) == "collimated" else "one"


def cap_half_angle(aperture_sr: float) -> float:
    """α (rad) of the cap of solid angle Ω (sr): Ω = 2π(1 − cos α), Ω ∈ (0, 2π]."""
    omega = positive("aperture_sr", aperture_sr)
    if omega > 2.0 * math.pi:
        raise DomainError(f"aperture_sr must be ≤ 2π, got {omega}")
    h = omega / (2.0 * math.pi)  # 1 − cos α, without cancellation
    return 2.0 * math.asin(math.sqrt(0.5 * h))


def _frame(w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Two unit tangents t1, t2 with (t1, t2, w) right-handed orthonormal (Duff et al.
    2017), continuous on the closed upper hemisphere."""
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    sign = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    t1 = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=-1)
    t2 = np.stack([b, sign + y * y * a, -y], axis=-1)
    return t1, t2


def aperture_integral(
    brdf_eval: BrdfEval,
    wi: ArrayLike,
    wo: ArrayLike,
    aperture_sr: float,
    weight: Weight | Source,
    *,
    order: int | tuple[int, int] = DEFAULT_ORDER,
) -> FloatArray:
    """A = ∫_cap f(wi, ω) w(ω) dω (sr · sr⁻¹ = dimensionless), shape broadcast(wi, wo)[:-1]
    (+ (3,) for RGB). ``weight``: "cos", "one", or a source (see `weight_for`).
    ``order``: (nodes in cos ψ, nodes in azimuth), or n for (n, 2n)."""
    kind: Weight = weight if isinstance(weight, str) else weight_for(weight)
    if kind not in ("cos", "one"):
        raise DomainError(f"weight must be 'cos' or 'one', got {weight!r}")
    omega_sr = positive("aperture_sr", aperture_sr)
    cap_half_angle(omega_sr)
    n_psi, n_chi = (order, 2 * order) if isinstance(order, int) else order
    if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in (n_psi, n_chi)):
        raise DomainError(f"order must be two positive integers, got {order!r}")
    a, b = direction_pair(wi, wo)
    lead = a.shape[:-1]
    wi_flat, wo_flat = a.reshape(-1, 3), b.reshape(-1, 3)

    x, wx = legendre(n_psi)
    h_cap = omega_sr / (2.0 * math.pi)
    h = 0.5 * h_cap * (1.0 - x)  # 1 − cos ψ at the nodes, in (0, 1 − cos α)
    cos_psi, sin_psi = 1.0 - h, np.sqrt(h * (2.0 - h))
    w_psi = 0.5 * h_cap * wx  # Gauss-Legendre in cos ψ on an interval of length h_cap
    trapezoid = (np.arange(n_chi) + 0.5) * (2.0 * math.pi / n_chi) - math.pi
    xg, wg = legendre(n_chi)

    block = max(1, _BLOCK // (n_psi * n_chi))
    out: list[FloatArray] = []
    for start in range(0, wo_flat.shape[0], block):
        wo_b = wo_flat[start : start + block]
        t1, t2 = _frame(wo_b)
        # On the ring ψ: z(χ) = cos ψ z_o + sin ψ ρ cos(χ − χ₀), ρ = |(t1_z, t2_z)|. Where
        # the ring dips below the horizon, integrate only over its visible arc
        # |χ − χ₀| ≤ arccos(−cos ψ z_o / (sin ψ ρ)) with Gauss-Legendre in χ.
        rho = np.hypot(t1[:, 2], t2[:, 2])[:, None]
        chi0 = np.arctan2(t2[:, 2], t1[:, 2])[:, None, None]
        top = cos_psi * wo_b[:, 2:3]  # (P, n_psi)
        side = sin_psi * rho
        full = top >= side
        half = np.arccos(np.clip(-top / np.where(full, 1.0, side), -1.0, 1.0))[..., None]
        chi = chi0 + np.where(full[..., None], trapezoid, half * xg)  # (P, n_psi, n_chi)
        w_chi = np.where(full[..., None], 2.0 * math.pi / n_chi, half * wg)
        cc, cs = sin_psi[:, None] * np.cos(chi), sin_psi[:, None] * np.sin(chi)
        cz = np.broadcast_to(cos_psi[:, None], chi.shape)
        dirs = (
            cz[..., None] * wo_b[:, None, None, :]
            + cc[..., None] * t1[:, None, None, :]
            + cs[..., None] * t2[:, None, None, :]
        ).reshape(len(wo_b), -1, 3)
        dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
        dirs[..., 2] = np.maximum(dirs[..., 2], 0.0)  # arc ends: rounding below the horizon
        w_node = (w_psi[:, None] * w_chi).reshape(len(wo_b), -1)
        wgt = w_node * dirs[..., 2] if kind == "cos" else w_node
        f = np.asarray(brdf_eval(wi_flat[start : start + block, None, :], dirs), np.float64)
        out.append(np.asarray(np.einsum("pm,pm...->p...", wgt, f), dtype=np.float64))
    result = np.concatenate(out, axis=0)
    return np.asarray(result.reshape(lead + result.shape[1:]), dtype=np.float64)
