"""Orthographic coordinates (‖h̄‖, φh, ‖k̄‖, φk) (Neumann 1999, Löw 2012; seed 000 eqs 3-4).

h = (ωi + ωo)/2 and k = (ωi − ωo)/2, unnormalized; a bar is the projection on the
tangent plane; φh, φk are the azimuths of h̄ and k̄. The inverse is
ω̄i = h̄ + k̄, ω̄o = h̄ − k̄ and ωz = sqrt(1 − ‖ω̄‖²) (seed 000 eqs 3-4).

Precision: a direction at elevation δ above the horizon has ‖ω̄‖² = 1 − δ², so its
z is recovered from a difference that float64 knows to about ε: the round trip error
of that direction is about ε/δ for δ ≫ √ε and about √ε below (see
docs/parametrizations.md). Everywhere else it keeps full precision.

Conventions: φh = 0 when h̄ = 0 (the mirror configuration), φk = 0 when k̄ = 0
(ωi = ωo). Domain: ‖h̄ ± k̄‖ ≤ 1, i.e. ‖h̄‖² + ‖k̄‖² + 2‖h̄‖‖k̄‖|cos(φk − φh)| ≤ 1.

Isotropic reduction (‖h̄‖, ‖k̄‖, φk − φh mod π): rotation about n (φh out) and
reciprocity (k → −k adds π to φk).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from gonio.params._arrays import TWO_PI, azimuth, wrap_pi, wrap_two_pi
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization, Parts
from gonio.types import BoolArray, FloatArray


def halfway_and_back(wi: Parts, wo: Parts) -> Parts:
    """h = (ωi + ωo)/2 and k = (ωi − ωo)/2 as (hx, hy, hz, kx, ky, kz)."""
    return (
        *(0.5 * (a + b) for a, b in zip(wi, wo, strict=True)),
        *(0.5 * (a - b) for a, b in zip(wi, wo, strict=True)),
    )


def plane_polar(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(‖(x, y)‖, azimuth) of tangent vectors; the azimuth is 0 for the zero vector."""
    return np.sqrt(x * x + y * y), azimuth(y, x)


def relative_azimuth_iso(phi_h: FloatArray, phi_k: FloatArray) -> FloatArray:
    """φk − φh wrapped to [0, 2π) and folded by reciprocity to [0, π)."""
    return wrap_pi(wrap_two_pi(phi_k - phi_h))


def lift(x: FloatArray, y: FloatArray, r2: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(x, y, sqrt(1 − r2)) with r2 = x² + y²; a tangent part longer than 1 (within
    the domain tolerance) is scaled back to the unit circle, giving z = 0."""
    over = r2 > 1.0
    if np.any(over):
        scale = np.where(over, 1.0 / np.sqrt(np.maximum(r2, 1.0)), 1.0)
        x, y = x * scale, y * scale
    return x, y, np.sqrt(np.maximum(1.0 - r2, 0.0))


class Orthographic(Parametrization):
    name = "orthographic"
    names = ("hbar", "phi_h", "kbar", "phi_k")
    bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, TWO_PI], [0.0, 1.0], [0.0, TWO_PI]])
    iso_names = ("hbar", "kbar", "phi_k_minus_phi_h")
    iso_bounds: ClassVar[FloatArray] = np.array([[0.0, 1.0], [0.0, 1.0], [0.0, np.pi]])
    iso_symmetry = "rotation about n (φh rotated out) and reciprocity (φk − φh folded to [0, π))"

    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        hx, hy, _, kx, ky, _ = halfway_and_back(wi, wo)
        return (*plane_polar(hx, hy), *plane_polar(kx, ky))

    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        c0, c1, c2, c3 = c
        hx, hy = c0 * np.cos(c1), c0 * np.sin(c1)
        kx, ky = c2 * np.cos(c3), c2 * np.sin(c3)
        xi, yi = hx + kx, hy + ky
        xo, yo = hx - kx, hy - ky
        ri2, ro2 = xi * xi + yi * yi, xo * xo + yo * yo
        limit = 1.0 + DOMAIN_TOLERANCE
        ok = (c0 >= 0.0) & (c2 >= 0.0) & (ri2 <= limit) & (ro2 <= limit)
        return (*lift(xi, yi, ri2), *lift(xo, yo, ro2)), ok

    def _reduce(self, c: Parts) -> Parts:
        return c[0], c[2], relative_azimuth_iso(c[1], c[3])
