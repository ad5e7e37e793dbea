"""Orthographic coordinates (‖h̄‖, φh, ‖k̄‖, φk) (Neumann 1999, Löw 2012;
Barla, Belcour & Pacanowski 2015, eqs 3-4).

h = (ωi + ωo)/2 and k = (ωi − ωo)/2, unnormalized; a bar is the projection on the
tangent plane; φh, φk are the azimuths of h̄ and k̄. The inverse is
ω̄i = h̄ + k̄, ω̄o = h̄ − k̄ and ωz = sqrt(1 − ‖ω̄‖²) (Barla et al. 2015, eqs 3-4).

Precision: a direction at elevation δ above the horizon has ‖ω̄‖² = 1 − δ², so its
z is recovered from a difference that float64 knows to about ε: the round trip error
of that direction is about ε/δ for δ ≫ √ε and about √ε below (see
docs/explanations/parametrizations.md). Everywhere else it keeps full precision.

Conventions: φh = 0 when h̄ = 0 (the mirror configuration), φk = 0 when k̄ = 0
(ωi = ωo). Domain: ‖h̄ ± k̄‖ ≤ 1, i.e. ‖h̄‖² + ‖k̄‖² + 2‖h̄‖‖k̄‖|cos(φk − φh)| ≤ 1.

Isotropic reduction (‖h̄‖, ‖k̄‖, φk − φh mod π): rotation about n (φh out) and
reciprocity (k → −k adds π to φk).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from gonio.params._arrays import TWO_PI, plane_polar, subset, wrap_pi, wrap_two_pi_in_place
from gonio.params._compensated import DD, dot2, exact_halfway_and_back, norm, one_minus_norm2
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization, Parts
from gonio.types import BoolArray, FloatArray

#: Below this z of either direction, the norms and azimuths are recomputed from the
#: exactly normalized pair in double-double (see `gonio.params._compensated`): there the
#: round trip amplifies a coordinate's error by 1/z, so ‖h̄‖, ‖k̄‖, ‖k‖ must be as close
#: to correctly rounded as float64 allows.
NEAR_HORIZON = 1e-4


def near_horizon(wi: Parts, wo: Parts) -> BoolArray:
    """Rows where either direction is within `NEAR_HORIZON` of the horizon."""
    return np.asarray(np.minimum(wi[2], wo[2]) < NEAR_HORIZON, dtype=np.bool_)


def dd_azimuth(x: DD, y: DD) -> FloatArray:
    """The azimuth of a tangent vector given in double-double (0 for the zero vector)."""
    return plane_polar(x[0] + x[1], y[0] + y[1])[1]


def relative_azimuth_iso(phi_h: FloatArray, phi_k: FloatArray) -> FloatArray:
    """φk − φh wrapped to [0, 2π) and folded by reciprocity to [0, π)."""
    return wrap_pi(wrap_two_pi_in_place(phi_k - phi_h))


def one_minus(r2: FloatArray) -> FloatArray:
    """sqrt(1 − r2), 0 where r2 ≥ 1."""
    return np.sqrt(np.maximum(1.0 - r2, 0.0))


def onto_circle(x: FloatArray, y: FloatArray, r2: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(x, y) with r2 = x² + y²; a tangent part longer than 1 (accepted within the domain
    tolerance) is scaled back to the unit circle (where its z is 0)."""
    over = r2 > 1.0
    if np.any(over):
        scale = np.where(over, 1.0 / np.sqrt(np.maximum(r2, 1.0)), 1.0)
        x, y = x * scale, y * scale
    return x, y


class Orthographic(Parametrization):
    name = "orthographic"
    names = ("hbar", "phi_h", "kbar", "phi_k")
    bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, TWO_PI], [0.0, 1.0], [0.0, TWO_PI]])
    iso_names = ("hbar", "kbar", "phi_k_minus_phi_h")
    iso_bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, 1.0], [0.0, np.pi]])
    iso_symmetry = "rotation about n (φh rotated out) and reciprocity (φk − φh folded to [0, π))"

    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        (xi, yi, _), (xo, yo, _) = wi, wo
        # 2h̄ and 2k̄: the azimuths do not see the factor, the norms are halved (exactly).
        hbar, phi_h = plane_polar(xi + xo, yi + yo)
        kbar, phi_k = plane_polar(xi - xo, yi - yo)
        hbar *= 0.5
        kbar *= 0.5
        sel = near_horizon(wi, wo)
        if np.any(sel):
            h = exact_halfway_and_back(subset(wi, sel), subset(wo, sel))
            hbar[sel], kbar[sel] = norm(h[0], h[1]), norm(h[3], h[4])
            phi_h[sel], phi_k[sel] = dd_azimuth(h[0], h[1]), dd_azimuth(h[3], h[4])
        return hbar, phi_h, kbar, phi_k

    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        c0, c1, c2, c3 = c
        ch, sh, ck, sk = np.cos(c1), np.sin(c1), np.cos(c3), np.sin(c3)
        hx, hy = c0 * ch, c0 * sh
        kx, ky = c2 * ck, c2 * sk
        xi, yi = hx + kx, hy + ky
        xo, yo = hx - kx, hy - ky
        ri2, ro2 = xi * xi + yi * yi, xo * xo + yo * yo
        limit = 1.0 + DOMAIN_TOLERANCE
        ok = (c0 >= 0.0) & (c2 >= 0.0) & (ri2 <= limit) & (ro2 <= limit)
        zi, zo = one_minus(ri2), one_minus(ro2)
        # Near the horizon z² = 1 − ‖ω̄‖² is a small difference: redo it in double-double
        # from the coordinates, leaving only the sine and cosine roundings.
        for z, r2, sign in ((zi, ri2, 1.0), (zo, ro2, -1.0)):
            sel = r2 > 1.0 - NEAR_HORIZON**2
            if np.any(sel):
                hb, kb = c0[sel], sign * c2[sel]
                x = dot2(hb, ch[sel], kb, ck[sel])
                y = dot2(hb, sh[sel], kb, sk[sel])
                z[sel] = np.sqrt(np.maximum(one_minus_norm2(x, y), 0.0))
        return (*onto_circle(xi, yi, ri2), zi, *onto_circle(xo, yo, ro2), zo), ok

    def _reduce(self, c: Parts) -> Parts:
        return c[0], c[2], relative_azimuth_iso(c[1], c[3])
