"""Rusinkiewicz's halfway/difference coordinates (θh, φh, θd, φd) (Barla, Belcour &
Pacanowski 2015, eqs 1-2).

As in Barla, Belcour & Pacanowski 2015, eqs 1-2:
ĥ = (ωi + ωo)/‖ωi + ωo‖ has polar angles (θh, φh); d̂ = rot_y(−θh) rot_z(−φh) ωi is
ωi in the frame where ĥ is the pole, with polar angles (θd, φd). The inverse is
ωi = rot_z(φh) rot_y(θh) d̂ and ωo = rot_z(φh) rot_y(θh) (−d̂x, −d̂y, d̂z), i.e. the
mirror of ωi about ĥ (Barla et al. 2015, eq. 2).

How the forward map keeps precision: with h = ωi + ωo and k = ωi − ωo (both exact for
nearly equal or nearly opposite directions, by Sterbenz's lemma), θh = atan2(‖h̄‖, hz),
θd = atan2(‖k‖, ‖h‖), and φd from k rotated into the h-frame (d̂'s tangent part is k's,
since ωi = ‖h‖ĥ + k with k ⊥ ĥ). No component is recovered through sqrt(1 − …), so
the round trip keeps full precision everywhere.

Conventions where an angle is undefined: φh = 0 when h̄ = 0 (ĥ = n); φd is then
measured from the x axis, and φd = 0 when ωi = ωo; when ωi = −ωo (opposite grazing
directions, h = 0) ĥ = n, θh = 0, θd = π/2 and φd = φi.

Domain: θh, θd ∈ [0, π/2] and tan θh tan θd |cos φd| ≤ 1 (both z components
cos θh cos θd ∓ sin θh sin θd cos φd non-negative).

Isotropic reduction (θh, θd, φd mod π): rotation about n (φh out) and reciprocity
(swapping ωi and ωo maps φd to φd + π).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from gonio.params._arrays import TWO_PI, azimuth, plane_polar, subset, wrap_pi
from gonio.params._compensated import exact_halfway_and_back
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization, Parts
from gonio.params.spherical import HALF_PI, clamp_theta, theta_in_range
from gonio.types import BoolArray, FloatArray

#: ‖ωi + ωo‖² below which h and k are recomputed from the exactly normalized directions.
NEAR_OPPOSITE = 0.25
#: ‖ωi + ωo‖ below the noise of that recomputation (a few ε²): the directions are
#: opposite, h = 0.
OPPOSITE = 16.0 * np.finfo(np.float64).eps ** 2


def _normalize_exactly(mask: BoolArray, wi: Parts, wo: Parts, sums: Parts) -> None:
    """Replace, where ``mask``, h = ωi + ωo and k = ωi − ωo by those of ω/‖ω‖, in place.

    A float64 direction is unit only to about ε, and near opposite directions the
    bisector ĥ of the pair moves by that defect divided by ‖h‖; the mirror of ωi about
    a bisector off by ε/‖h‖ misses ωo by as much. From the exactly normalized pair h is
    known to a few ε² (`exact_halfway_and_back`); its part along k, which is 0 for unit
    vectors, is then removed, so that ĥ ⊥ ωi holds however small ‖h‖ is and the mirror
    of ωi about ĥ is ωo to a few ε². Below that noise, h = 0.
    """
    parts = exact_halfway_and_back(subset(wi, mask), subset(wo, mask))
    h = [2.0 * (hi + lo) for hi, lo in parts[:3]]
    k = [2.0 * (hi + lo) for hi, lo in parts[3:]]
    along = (h[0] * k[0] + h[1] * k[1] + h[2] * k[2]) / (k[0] * k[0] + k[1] * k[1] + k[2] * k[2])
    h = [a - along * b for a, b in zip(h, k, strict=True)]
    opposite = h[0] * h[0] + h[1] * h[1] + h[2] * h[2] < OPPOSITE * OPPOSITE
    for target, value in zip(sums[:3], h, strict=True):
        target[mask] = np.where(opposite, 0.0, value)
    for target, value in zip(sums[3:], k, strict=True):
        target[mask] = value


class Rusinkiewicz(Parametrization):
    name = "rusinkiewicz"
    names = ("theta_h", "phi_h", "theta_d", "phi_d")
    bounds: ClassVar[FloatArray] = np.array(
        [[0.0, HALF_PI], [0.0, TWO_PI], [0.0, HALF_PI], [0.0, TWO_PI]]
    )
    iso_names = ("theta_h", "theta_d", "phi_d")
    iso_bounds: ClassVar[FloatArray] = np.array([[0.0, HALF_PI], [0.0, HALF_PI], [0.0, np.pi]])
    iso_symmetry = "rotation about n (φh rotated out) and reciprocity (φd folded to [0, π))"

    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        (xi, yi, zi), (xo, yo, zo) = wi, wo
        hx, hy, hz = xi + xo, yi + yo, zi + zo
        kx, ky, kz = xi - xo, yi - yo, zi - zo
        near_opposite = hx * hx + hy * hy + hz * hz < NEAR_OPPOSITE
        if np.any(near_opposite):
            _normalize_exactly(near_opposite, wi, wo, (hx, hy, hz, kx, ky, kz))
        hbar, phi_h = plane_polar(hx, hy)  # φh = 0 where h̄ = 0, underflow included
        hbar2 = hbar * hbar
        hnorm = np.sqrt(hbar2 + hz * hz)
        knorm = np.sqrt(kx * kx + ky * ky + kz * kz)
        theta_h = np.arctan2(hbar, hz)
        theta_d = np.arctan2(knorm, hnorm)
        # d̂'s tangent part is k in the h-frame: (k·e1, k·e2) with e1 = rot_z(φh) rot_y(θh) x,
        # e2 = rot_z(φh) y, both scaled here by ‖h̄‖‖h‖ > 0. With h̄ = 0 the frame is the
        # sample frame (φh = 0, θh = 0) and φd is k's azimuth.
        d_x = hz * (kx * hx + ky * hy) - hbar2 * kz
        d_y = (ky * hx - kx * hy) * hnorm
        pole = hbar == 0.0
        if np.any(pole):
            d_x[pole], d_y[pole] = kx[pole], ky[pole]
        phi_d = azimuth(d_y, d_x)
        return theta_h, phi_h, theta_d, phi_d

    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        c0, c1, c2, c3 = c
        th, td = clamp_theta(c0), clamp_theta(c2)
        st, ct = np.sin(th), np.cos(th)
        sp, cp = np.sin(c1), np.cos(c1)
        sd, cd = np.sin(td), np.cos(td)
        dx, dy = sd * np.cos(c3), sd * np.sin(c3)
        # rot_y(θh) of (±dx, ±dy, cd): x' = ct·(±dx) + st·cd, z' = −st·(±dx) + ct·cd.
        a, b = st * cd, ct * cd
        u, w = ct * dx, st * dx
        zi, zo = b - w, b + w
        ok = theta_in_range(c0) & theta_in_range(c2) & (np.minimum(zi, zo) >= -DOMAIN_TOLERANCE)
        xi_, xo_ = u + a, a - u
        out = (cp * xi_ - sp * dy, sp * xi_ + cp * dy, np.maximum(zi, 0.0))
        return (*out, cp * xo_ + sp * dy, sp * xo_ - cp * dy, np.maximum(zo, 0.0)), ok

    def _reduce(self, c: Parts) -> Parts:
        return c[0], c[2], wrap_pi(c[3])
