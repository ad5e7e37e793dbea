"""Spatial integration for a proximal point source (the proximal point law of
the lecture notes on reflectance models).

The source sits at s = r·wi from the sample centre. A surface point x (sample plane,
z = 0) receives E(x) = I · cos θ(x) / |s − x|² = I · r cos θi / |s − x|³ (the proximal
point law of the lecture notes on lighting and reflectance models) from the
direction ωi(x) = (s − x)/|s − x|; the distant detector looks from the fixed wo over
its seen ellipse (F/(2 cos θo) × F/2). Power into the aperture:

    Φ = Ω · ∫_{seen ∩ sample} f(ωi(x), wo) · E(x) · cos θo dA.

Lengths cancel (E dA is I times a solid angle), so everything is in mm inside.

Quadrature: polar coordinates about the centre. The region is star-shaped with radius
R(β) = min over the seen ellipse and the disc; its kinks (where they cross) and the
quadrant boundaries split [0, 2π) into 8 pieces, each with `order[0]` Gauss-Legendre
nodes in β; along each ray `order[1]` Gauss-Legendre nodes in ρ ∈ [0, R(β)]. Default
(8, 12): 768 BRDF evaluations per pair. Accuracy: see docs/explanations/radiometry.md.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.brdf import legendre
from gonio.errors import DomainError
from gonio.radiometry._checks import cosine, direction_pair, positive
from gonio.radiometry._ellipses import Form, azimuth, crossings, ellipse_form, quadratic
from gonio.radiometry.ideal import DetectorOptics, PointSource, radiant_power_checked
from gonio.types import ArrayLike, BrdfEval, FloatArray

#: Default quadrature order: (Gauss-Legendre nodes per azimuth piece, radial nodes).
DEFAULT_ORDER = (8, 12)
#: Pairs × nodes evaluated at once (bounds memory; the loop runs over blocks, not pairs).
_BLOCK = 1 << 17


def _order(order: tuple[int, int]) -> tuple[int, int]:
    n_az, n_r = order
    if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in (n_az, n_r)):
        raise DomainError(f"order must be two positive integers, got {order!r}")
    return n_az, n_r


def _nodes(
    wo: FloatArray, fov_mm: float, sample_mm: float, n_az: int, n_r: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Sample-plane nodes (P, M, 2) in mm and area weights (P, M) (mm², summing to the
    region's area) for pairs' wo (P, 3); M = 8 · n_az · n_r."""
    co = cosine(wo)
    cos_o, sin_o = azimuth(wo)
    seen = ellipse_form(2.0 * co / fov_mm, np.full_like(co, 2.0 / fov_mm), cos_o, sin_o)
    inv_r2 = (2.0 / sample_mm) ** 2
    disc = Form(*(np.full_like(co, v) for v in (inv_r2, inv_r2, 0.0, inv_r2 * inv_r2)))
    c1, c2 = crossings(seen, disc)
    fixed = [np.full_like(co, k * 0.5 * math.pi) for k in range(4)]
    edges = np.sort(np.stack([*fixed, c1, c2, c1 + math.pi, c2 + math.pi], axis=-1), axis=-1)
    edges = np.concatenate([edges, np.full_like(co, 2.0 * math.pi)[:, None]], axis=-1)
    lo, hi = edges[:, :-1, None], edges[:, 1:, None]  # (P, 8, 1)
    xa, wa = legendre(n_az)
    beta = (0.5 * (lo + hi) + 0.5 * (hi - lo) * xa).reshape(len(co), -1)  # (P, 8 n_az)
    w_beta = (0.5 * (hi - lo) * wa).reshape(len(co), -1)
    cb, sb = np.cos(beta), np.sin(beta)
    q = np.maximum(quadratic(Form(*(v[:, None] for v in seen)), cb, sb), inv_r2)
    radius = 1.0 / np.sqrt(q)  # (P, 8 n_az)
    xr, wr = legendre(n_r)
    rho = 0.5 * radius[..., None] * (1.0 + xr)  # (P, 8 n_az, n_r)
    weight = w_beta[..., None] * 0.5 * radius[..., None] * wr * rho
    points = np.stack([rho * cb[..., None], rho * sb[..., None]], axis=-1)
    p = len(co)
    return points.reshape(p, -1, 2), weight.reshape(p, -1), co


def point_source_power(
    source: PointSource,
    optics: DetectorOptics,
    sample_diameter_mm: float,
    brdf_eval: BrdfEval,
    wi: ArrayLike,
    wo: ArrayLike,
    *,
    order: tuple[int, int] = DEFAULT_ORDER,
) -> FloatArray:
    """Φ (W) collected from a proximal point source over the seen part of the sample.

    ``brdf_eval(wi, wo)`` maps directions (..., 3) to f (sr⁻¹) of shape (...) or (..., 3)
    (e.g. a model's ``eval``). Result: shape broadcast(wi, wo)[:-1], plus (3,) for RGB.
    See the module for the integral and the quadrature.
    """
    if not isinstance(source, PointSource):
        raise DomainError(f"point_source_power needs a PointSource, got {source!r}")
    if not isinstance(optics, DetectorOptics):
        raise DomainError(f"optics must be a DetectorOptics, got {optics!r}")
    sample_mm = positive("sample_diameter_mm", sample_diameter_mm)
    n_az, n_r = _order(order)
    a, b = direction_pair(wi, wo)
    lead = a.shape[:-1]
    wi_flat, wo_flat = a.reshape(-1, 3), b.reshape(-1, 3)
    count = wi_flat.shape[0]
    per_pair = 8 * n_az * n_r
    block = max(1, _BLOCK // per_pair)
    out: list[FloatArray] = []
    for start in range(0, count, block):
        wi_b, wo_b = wi_flat[start : start + block], wo_flat[start : start + block]
        points, weight, co = _nodes(wo_b, optics.fov_diameter_mm, sample_mm, n_az, n_r)
        src = source.distance_mm * wi_b  # (P, 3), z = r cos θi ≥ 0
        dx = src[:, None, 0] - points[..., 0]
        dy = src[:, None, 1] - points[..., 1]
        dz = np.broadcast_to(np.maximum(src[:, None, 2], 0.0), dx.shape)
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        safe = np.where(dist > 0.0, dist, 1.0)
        omega = np.stack([dx / safe, dy / safe, dz / safe], axis=-1)
        omega = np.where((dist > 0.0)[..., None], omega, wi_b[:, None, :])
        # I r cos θi / d³: the point law with cos θ(x) = r cos θi / d.
        irr = np.where(dist > 0.0, dz / (safe * safe * safe), 0.0)
        f = np.asarray(brdf_eval(omega, wo_b[:, None, :]), dtype=np.float64)
        w = weight * irr * co[:, None]
        total = np.einsum("pm,pm...->p...", w, f)
        out.append(np.asarray(total, dtype=np.float64))
    result = np.concatenate(out, axis=0) if out else np.zeros((0,))
    result = result * (source.intensity_w_sr * optics.aperture_sr)
    return np.asarray(result.reshape(lead + result.shape[1:]), dtype=np.float64)


def _constant(wi: FloatArray, wo: FloatArray) -> FloatArray:
    return np.ones(np.broadcast_shapes(wi.shape, wo.shape)[:-1])


def spot_ratio(
    source: PointSource,
    optics: DetectorOptics,
    sample_diameter_mm: float,
    wi: ArrayLike,
    wo: ArrayLike,
    brdf_eval: BrdfEval | None = None,
    *,
    order: tuple[int, int] = DEFAULT_ORDER,
) -> FloatArray:
    """Φ / (f(wi, wo) · G): `point_source_power` over the ideal chain's power
    (dimensionless), shape broadcast(wi, wo)[:-1] (+ (3,) for RGB).

    ``brdf_eval`` None: a constant f, the geometry alone (the irradiance falling off as
    cos θ(x)/|s − x|² across the seen part of the sample, and a view past its edge); with
    a BRDF, also its variation over the spread of incidence across the spot. Tends to 1
    quadratically in F/r with the view on the sample; NaN where the ideal power is 0.
    """
    f_eval = _constant if brdf_eval is None else brdf_eval
    a, b = direction_pair(wi, wo)
    ideal = radiant_power_checked(source, optics, f_eval(a, b), a, b)
    power = point_source_power(source, optics, sample_diameter_mm, f_eval, a, b, order=order)
    safe = np.where(ideal != 0.0, ideal, 1.0)
    return np.asarray(np.where(ideal != 0.0, power / safe, np.nan), dtype=np.float64)
