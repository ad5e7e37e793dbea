"""How each parametrization's forward map stretches a direction error: its Jacobian,
exactly (analytic derivatives evaluated in float64), and its condition number.

Two Jacobians of the coordinates c = forward(ωi, ωo), each (..., 4, 4):

- `angle_jacobian`: ∂c/∂(θi, φi, θo, φo), the pair's spherical angles (radians).
- `tangent_jacobian`: ∂c/∂(si, ti, so, to), arc length (radians) along the orthonormal
  tangent frame (e_θ, e_φ) of each direction, e_θ = ∂ω/∂θ, e_φ = ∂ω/∂φ / sin θ. This
  is the one whose singular values say how much the map stretches a direction error,
  since it does not inherit the angle chart's own singularity (moving ω by δ at θ = d
  changes φ by up to δ/d, so ∂c/∂φ → 0 at the pole for every parametrization). Any
  other orthonormal tangent frame gives the same singular values. The two differ only
  by the column scaling angle = tangent · diag(1, sin θi, 1, sin θo).

Units: the radii of orthographic and hybrid (‖h̄‖, ‖k̄‖, ‖k‖ ≤ 1) are dimensionless,
like the angles, and enter the singular values as they are.

The derivatives are those of each coordinate's definition (docs/explanations/parametrizations.md)
extended off the sphere as the float64 code computes them (polar angles and azimuths
of h = ωi + ωo, k = ωi − ωo, norms of their parts), chained by hand; none is a finite
difference. At a configuration where a coordinate is not differentiable (an azimuth or
polar angle of a zero vector, a norm at zero: ω = n for spherical, h̄ = 0, k = 0 or
h = 0 for the others) the Jacobian does not exist and `DomainError` names the pair.
Near such a point the entries grow like 1/d at distance d; a float64 pair there is
itself known only to ε, so entries carry a relative error of about ε/d (2e-4 at 1e-12).
"""

from __future__ import annotations

import numpy as np

from gonio.directions import pair_components
from gonio.errors import DomainError
from gonio.params import get
from gonio.params._compensated import exact_halfway_and_back
from gonio.types import ArrayLike, FloatArray

Vec = tuple[FloatArray, FloatArray, FloatArray]
Grad = FloatArray  # (N, 3): a scalar's gradient with respect to one 3-vector


def _zero(n: int) -> Grad:
    return np.zeros((n, 3))


def _tangent_norm(v: Vec, what: str) -> FloatArray:
    """‖v̄‖, required nonzero; as in the forward maps, a tangent part whose square
    underflows (below about 1e-154) counts as zero (its azimuth is 0 there)."""
    r = np.hypot(v[0], v[1])
    _require(r * r > 0.0, what)
    return r


def _require(ok: np.ndarray, what: str) -> None:
    if not np.all(ok):
        first = int(np.argmin(ok))
        raise DomainError(
            f"the Jacobian does not exist at pair {first} (and {int(np.size(ok) - np.sum(ok))} "
            f"in all): {what}; move the pair off it"
        )


def _radius_grad(v: Vec, r: FloatArray) -> Grad:
    """∇‖v̄‖ = (v̄/‖v̄‖, 0)."""
    return np.stack([v[0] / r, v[1] / r, np.zeros_like(r)], axis=-1)


def _azimuth_grad(v: Vec, r: FloatArray) -> Grad:
    """∇ atan2(vy, vx) = (−vy, vx, 0)/‖v̄‖² (as (unit)/‖v̄‖: no overflow)."""
    return np.stack([-v[1] / r / r, v[0] / r / r, np.zeros_like(r)], axis=-1)


def _polar_grad(v: Vec, r: FloatArray) -> Grad:
    """∇ atan2(‖v̄‖, vz) = (vz v̄/‖v̄‖, −‖v̄‖)/‖v‖²."""
    n = np.hypot(r, v[2])
    c, s = v[2] / n, r / n
    return np.stack([c * v[0] / r / n, c * v[1] / r / n, -s / n], axis=-1)


def _norm_grad(v: Vec, what: str) -> Grad:
    """∇‖v‖ = v/‖v‖."""
    n = np.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
    _require(n > 0.0, what)
    return np.stack([v[0] / n, v[1] / n, v[2] / n], axis=-1)


def _phi_d_grads(h: Vec, k: Vec) -> tuple[Grad, Grad]:
    """∇_h φd and ∇_k φd of Rusinkiewicz's φd = atan2(dy, dx) with
    dx = hz (k·h̄) − ‖h̄‖² kz and dy = (ky hx − kx hy) ‖h‖ (gonio.params.rusinkiewicz);
    both are homogeneous, so h and k are first scaled to unit length."""
    hn = np.sqrt(h[0] ** 2 + h[1] ** 2 + h[2] ** 2)
    kn = np.sqrt(k[0] ** 2 + k[1] ** 2 + k[2] ** 2)
    hx, hy, hz = (c / hn for c in h)
    kx, ky, kz = (c / kn for c in k)
    hb2 = hx * hx + hy * hy
    dx = hz * (kx * hx + ky * hy) - hb2 * kz
    cross = ky * hx - kx * hy
    dy = cross  # ‖ĥ‖ = 1
    den = dx * dx + dy * dy
    _require(den > 0.0, "φd is undefined (k has no part across ĥ)")
    ddx_h = np.stack([hz * kx - 2 * hx * kz, hz * ky - 2 * hy * kz, kx * hx + ky * hy], axis=-1)
    ddx_k = np.stack([hz * hx, hz * hy, -hb2], axis=-1)
    ddy_h = np.stack([ky + cross * hx, -kx + cross * hy, cross * hz], axis=-1)
    ddy_k = np.stack([-hy, hx, np.zeros_like(hx)], axis=-1)
    w_x, w_y = (-dy / den)[:, None], (dx / den)[:, None]
    return (w_x * ddx_h + w_y * ddy_h) / hn[:, None], (w_x * ddx_k + w_y * ddy_k) / kn[:, None]


def _rows(name: str, wi: Vec, wo: Vec) -> list[tuple[Grad, Grad]]:
    """Per coordinate, its gradients with respect to (ωi, ωo)."""
    n = len(wi[0])
    if name == "spherical":
        ri = _tangent_norm(wi, "ωi = n (φi is undefined)")
        ro = _tangent_norm(wo, "ωo = n (φo is undefined)")
        zero = _zero(n)
        return [
            (_polar_grad(wi, ri), zero),
            (_azimuth_grad(wi, ri), zero),
            (zero, _polar_grad(wo, ro)),
            (zero, _azimuth_grad(wo, ro)),
        ]
    # 2h and 2k of the exactly normalized pair: near opposite or equal directions the
    # unit defect of a float64 pair (ε) would otherwise turn h̄ or k̄ by ε/‖h̄‖.
    parts = [2.0 * (hi + lo) for hi, lo in exact_halfway_and_back(wi, wo)]
    h: Vec = (parts[0], parts[1], parts[2])
    k: Vec = (parts[3], parts[4], parts[5])
    rh = _tangent_norm(h, "h̄ = 0, the mirror configuration (φh is undefined)")
    if name == "rusinkiewicz":
        rows_h = [_polar_grad(h, rh), _azimuth_grad(h, rh)]  # θh, φh: of h alone
        hg = _norm_grad(h, "h = 0, opposite directions (ĥ is undefined)")
        kg = _norm_grad(k, "k = 0, retro-reflection (φd is undefined)")
        hn = np.sqrt(h[0] ** 2 + h[1] ** 2 + h[2] ** 2)[:, None]
        kn = np.sqrt(k[0] ** 2 + k[1] ** 2 + k[2] ** 2)[:, None]
        s = hn * hn + kn * kn  # θd = atan2(‖k‖, ‖h‖)
        td_h, td_k = -kn * hg / s, hn * kg / s
        pd_h, pd_k = _phi_d_grads(h, k)
        out = [(g, g) for g in rows_h]
        return [*out[:2], (td_h + td_k, td_h - td_k), (pd_h + pd_k, pd_h - pd_k)]
    # Orthographic and hybrid use h and k halved: ∂/∂ωi = ½(∇h + ∇k), ∂/∂ωo = ½(∇h − ∇k).
    radius_h, phi_h = _radius_grad(h, rh), _azimuth_grad(h, rh)
    if name == "orthographic":
        rk = _tangent_norm(k, "k̄ = 0, retro-reflection (φk is undefined)")
        radius_k = _radius_grad(k, rk)
    elif name == "hybrid":
        radius_k = _norm_grad(k, "k = 0, retro-reflection (φk is undefined)")
        rk = _tangent_norm(k, "k̄ = 0, retro-reflection (φk is undefined)")
    else:
        raise AssertionError(name)  # `cartesian_jacobian` checked the name
    phi_k = _azimuth_grad(k, rk)
    # The norms are of h = (ωi + ωo)/2 and k, half those of the sums used here: ½ ∇;
    # the azimuths do not see the factor.
    return [
        (0.5 * radius_h, 0.5 * radius_h),
        (phi_h, phi_h),
        (0.5 * radius_k, -0.5 * radius_k),
        (phi_k, -phi_k),
    ]


def cartesian_jacobian(name: str, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """∂c/∂(ωi, ωo) (..., 4, 6) at unit directions (..., 3) (see the module docstring)."""
    get(name)  # UnknownNameError for a name that is not registered
    lead, a, b = pair_components(wi, wo)
    rows = _rows(name, a, b)
    out = np.stack([np.concatenate([gi, go], axis=-1) for gi, go in rows], axis=1)
    return np.asarray(out.reshape((*lead, 4, 6)), dtype=np.float64)


def tangent_frame(w: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """(e_θ, e_φ) (..., 3) each: orthonormal tangent vectors of unit ``w`` along θ and φ
    (at the pole, those of φ = 0: e_θ = x, e_φ = y)."""
    w = np.asarray(w, dtype=np.float64)
    r = np.hypot(w[..., 0], w[..., 1])
    pole = r == 0.0
    safe = np.where(pole, 1.0, r)
    c, s = np.where(pole, 1.0, w[..., 0] / safe), np.where(pole, 0.0, w[..., 1] / safe)
    z = w[..., 2]
    e_theta = np.stack([z * c, z * s, -r], axis=-1)
    e_phi = np.stack([-s, c, np.zeros_like(c)], axis=-1)
    return e_theta, e_phi


def pair_frame(wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """(..., 6, 4): the columns e_θi, e_φi (in the ωi rows), e_θo, e_φo (in the ωo rows)."""
    (ti, pi), (to, po) = tangent_frame(wi), tangent_frame(wo)
    zero = np.zeros_like(ti)
    top = np.stack([ti, pi, zero, zero], axis=-1)
    bottom = np.stack([zero, zero, to, po], axis=-1)
    return np.asarray(np.concatenate([top, bottom], axis=-2), dtype=np.float64)


def tangent_jacobian(name: str, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """∂c/∂(si, ti, so, to) (..., 4, 4): arc length along (e_θ, e_φ) of each direction."""
    return np.asarray(cartesian_jacobian(name, wi, wo) @ pair_frame(wi, wo), dtype=np.float64)


def angle_jacobian(name: str, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """∂c/∂(θi, φi, θo, φo) (..., 4, 4)."""
    wi, wo = np.asarray(wi, np.float64), np.asarray(wo, np.float64)
    sin_i, sin_o = np.hypot(wi[..., 0], wi[..., 1]), np.hypot(wo[..., 0], wo[..., 1])
    one = np.ones_like(sin_i * sin_o)
    scale = np.stack(np.broadcast_arrays(one, sin_i, one, sin_o), axis=-1)
    return np.asarray(tangent_jacobian(name, wi, wo) * scale[..., None, :], dtype=np.float64)


def singular_values(jacobian: ArrayLike) -> FloatArray:
    """Singular values (..., 4), largest first, of stacked 4×4 Jacobians."""
    return np.asarray(np.linalg.svd(np.asarray(jacobian, np.float64), compute_uv=False), np.float64)


def condition_number(jacobian: ArrayLike) -> FloatArray:
    """σmax/σmin (...) of stacked Jacobians; inf where σmin = 0 (a singular map)."""
    s = singular_values(jacobian)
    return np.asarray(
        np.divide(s[..., 0], s[..., -1], out=np.full(s.shape[:-1], np.inf), where=s[..., -1] > 0),
        dtype=np.float64,
    )
