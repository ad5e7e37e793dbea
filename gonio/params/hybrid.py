"""Hybrid coordinates (‖h̄‖, φh, ‖k‖, φk) (Barla, Belcour &
Pacanowski 2015, eqs 5-6 and appendix, after Stark 2005).

h = (ωi + ωo)/2 and k = (ωi − ωo)/2, unnormalized (‖h‖² + ‖k‖² = 1, h·k = 0); h̄, k̄
are their projections on the tangent plane, φh, φk the azimuths of h̄ and k̄ (φk is
well defined: in the closed upper hemisphere k̄ = 0 only when k = 0). The inverse
rebuilds h = (h̄, hz) with hz = sqrt(1 − ‖k‖² − ‖h̄‖²) and k = ‖k‖ (sin θk k̂̄, cos θk)
from h·k = 0, then ωi = h + k, ωo = h − k (Barla et al. 2015, eqs 5-6).

θk, done right. The appendix's θk = tan⁻¹(−hz / (‖h̄‖ cos(φh − φk))) needs its
quadrant: sin θk ≥ 0 because φk is k̄'s own azimuth, so
(sin θk, cos θk) = (hz, −a)/N with a = ‖h̄‖ cos(φk − φh) and N = sqrt(hz² + a²).
Read as a principal-value arctangent it returns −k whenever ωi is lower than ωo
(ωi and ωo swapped). Near grazing a second failure remains even with the quadrant
right: when both directions approach the horizon, hz and a both approach 0 and each
is known only to about √ε and ε, so θk = atan2(hz, −a) can land anywhere in [0, π]
and kz = ‖k‖ cos θk anywhere in [−‖k‖, ‖k‖]: a different configuration. The fix is
the domain itself: |kz| ≤ hz (both z components are non-negative), so a kz beyond
[−hz, hz] by more than the noise is put on the edge with ‖k‖ kept; the error then
stays at the √ε that hz itself carries.

Precision: hz is recovered from 1 − ‖k‖² − ‖h̄‖² (evaluated as (1 − x)(1 + x) − y² with
x the larger of the two, exact for x near 1), so when both directions are within δ of
the horizon the round trip error is about ε/δ for δ ≫ √ε and about √ε below. With
one direction grazing and the other not, hz is O(1) and full precision is kept.

Conventions: φh = 0 when h̄ = 0 (the mirror configuration); φk = 0 when k = 0 (ωi = ωo);
θk = π/2 when hz = a = 0 (both directions on the horizon).

Domain (derived in docs/explanations/parametrizations.md): with z = 1 − ‖h̄‖² − ‖k‖² and
c = ‖h̄‖² cos²(φk − φh), valid iff z ≥ 0 and ‖k‖² c ≤ z (z + c).

Isotropic reduction (‖h̄‖, ‖k‖, φk − φh mod π): rotation about n (φh out) and
reciprocity (k → −k adds π to φk).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from gonio.params._arrays import TWO_PI, plane_polar, subset
from gonio.params._compensated import exact_halfway_and_back, norm
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization, Parts
from gonio.params.orthographic import (
    dd_azimuth,
    near_horizon,
    relative_azimuth_iso,
)
from gonio.types import BoolArray, FloatArray


def one_minus_squares(x: FloatArray, y: FloatArray) -> FloatArray:
    """1 − x² − y² for x, y ≥ 0, as (1 − m)(1 + m) − s² with m = max(x, y), s = min.

    1 − m is exact for m ∈ [1/2, 1] (Sterbenz), so near the unit circle the result
    carries an error of a few ε·(s² + 1 − m²) instead of the ε of the naive form;
    for m < 1/2 both forms are good to about ε.
    """
    m, s = np.maximum(x, y), np.minimum(x, y)
    return np.asarray((1.0 - m) * (1.0 + m) - s * s, dtype=np.float64)


#: How far |kz| may exceed hz before θk is treated as noise: about √ε, the
#: precision hz keeps as both directions reach the horizon.
CLAMP_THRESHOLD = 2.0**-26


class Hybrid(Parametrization):
    name = "hybrid"
    names = ("hbar", "phi_h", "k", "phi_k")
    bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, TWO_PI], [0.0, 1.0], [0.0, TWO_PI]])
    iso_names = ("hbar", "k", "phi_k_minus_phi_h")
    iso_bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, 1.0], [0.0, np.pi]])
    iso_symmetry = "rotation about n (φh rotated out) and reciprocity (φk − φh folded to [0, π))"

    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        (xi, yi, zi), (xo, yo, zo) = wi, wo
        # 2h̄ and 2k: the azimuths do not see the factor, the norms are halved (exactly).
        hbar, phi_h = plane_polar(xi + xo, yi + yo)
        kbar, phi_k = plane_polar(xi - xo, yi - yo)
        kz = zi - zo
        kbar *= kbar
        kz *= kz
        kbar += kz
        knorm = np.sqrt(kbar, out=kbar)
        hbar *= 0.5
        knorm *= 0.5
        sel = near_horizon(wi, wo)
        if np.any(sel):
            h = exact_halfway_and_back(subset(wi, sel), subset(wo, sel))
            hbar[sel], knorm[sel] = norm(h[0], h[1]), norm(h[3], h[4], h[5])
            phi_h[sel], phi_k[sel] = dd_azimuth(h[0], h[1]), dd_azimuth(h[3], h[4])
        return hbar, phi_h, knorm, phi_k

    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        c0, c1, c2, c3 = c
        ch, sh = np.cos(c1), np.sin(c1)
        ck, sk = np.cos(c3), np.sin(c3)
        z = one_minus_squares(c0, c2)
        hz = np.sqrt(np.maximum(z, 0.0))
        a = c0 * (ch * ck + sh * sk)  # ‖h̄‖ cos(φk − φh)
        a2 = a * a
        # The exact domain condition ‖k‖² a² ≤ z (z + a²), with z relaxed by the rounding
        # margin (z enters it monotonically).
        zr = z + DOMAIN_TOLERANCE
        ok = (c0 >= 0.0) & (c2 >= 0.0) & (zr >= 0.0) & (c2 * c2 * a2 <= zr * (zr + a2))
        # (sin θk, cos θk) = (hz, −a)/N; N = 0 only with both directions on the horizon,
        # where θk = π/2 (adding 1 to numerator and denominator gives exactly that).
        degenerate = hz * hz + a2 == 0.0
        norm = np.sqrt(hz * hz + a2) + degenerate
        kbar = c2 * ((hz + degenerate) / norm)
        kz = -c2 * (a / norm)
        # |kz| > hz would put a direction below the horizon; only rounding can do that.
        # Beyond the noise hz carries (about √ε) θk itself is noise (hz and a both ~ 0):
        # put kz on the domain's edge and keep ‖k‖ through ‖k̄‖. Within it, keep θk
        # (there ‖k̄‖ = ‖k‖ hz/N is the accurate one) and only clip the z components.
        far = np.abs(kz) - hz > CLAMP_THRESHOLD
        any_far = bool(np.any(far))
        if any_far:
            e = hz[far]
            kz[far] = np.copysign(e, kz[far])
            kbar[far] = np.sqrt(np.maximum((c2[far] - e) * (c2[far] + e), 0.0))
        hx, hy = c0 * ch, c0 * sh
        kx, ky = kbar * ck, kbar * sk
        zi, zo = np.maximum(hz + kz, 0.0), np.maximum(hz - kz, 0.0)
        out = (hx + kx, hy + ky, zi, hx - kx, hy - ky, zo)
        if any_far:
            # h·k = 0 no longer holds exactly there (z may also have been negative within
            # the domain tolerance): put each direction back on the unit sphere.
            for x, y, z in (out[:3], out[3:]):
                length = np.sqrt(x[far] ** 2 + y[far] ** 2 + z[far] ** 2)
                length[length == 0.0] = 1.0  # only for rows `ok` rejects (e.g. ‖k‖ < 0)
                x[far], y[far], z[far] = x[far] / length, y[far] / length, z[far] / length
        return out, ok

    def _reduce(self, c: Parts) -> Parts:
        return c[0], c[2], relative_azimuth_iso(c[1], c[3])
