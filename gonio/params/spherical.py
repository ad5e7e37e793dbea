"""Spherical coordinates of both directions: (θi, φi, θo, φo).

θ is the polar angle from the normal, in [0, π/2]; φ the azimuth from the sample's x
axis, in [0, 2π); φ = 0 by convention where θ = 0. Every map here is a composition
of well-conditioned trigonometric functions, so the round trip keeps full precision
everywhere, grazing and normal incidence included.

Isotropic reduction (θi, θo, φo − φi mod 2π): rotation invariance about n only. The
reciprocity swap (θi, θo, Δφ) → (θo, θi, −Δφ) is not a fold of one coordinate, and
bilateral symmetry (which would allow |Δφ| ∈ [0, π], as in the ρ(θi, θo, |φi − φo|) of
Barla, Belcour & Pacanowski 2015) is not assumed.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from gonio.params._arrays import TWO_PI, plane_polar, wrap_two_pi_in_place
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization, Parts
from gonio.types import BoolArray, FloatArray

HALF_PI = 0.5 * np.pi


def polar(x: FloatArray, y: FloatArray, z: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(θ, φ) of unit vectors: θ = atan2(‖(x, y)‖, z), φ = azimuth (0 where θ = 0)."""
    r, phi = plane_polar(x, y)
    return np.arctan2(r, z), phi


def theta_in_range(theta: FloatArray) -> BoolArray:
    """θ ∈ [0, π/2] up to the domain tolerance."""
    return (theta >= -DOMAIN_TOLERANCE) & (theta <= HALF_PI + DOMAIN_TOLERANCE)


def clamp_theta(theta: FloatArray) -> FloatArray:
    """θ limited to [0, π/2] (for coordinates accepted within the domain tolerance)."""
    return np.clip(theta, 0.0, HALF_PI)


class Spherical(Parametrization):
    name = "spherical"
    names = ("theta_i", "phi_i", "theta_o", "phi_o")
    bounds: ClassVar[FloatArray] = np.array(
        [[0.0, HALF_PI], [0.0, TWO_PI], [0.0, HALF_PI], [0.0, TWO_PI]]
    )
    iso_names = ("theta_i", "theta_o", "phi_o_minus_phi_i")
    iso_bounds: ClassVar[FloatArray] = np.array([[0.0, HALF_PI], [0.0, HALF_PI], [0.0, TWO_PI]])
    iso_symmetry = "rotation about n (φi rotated out); reciprocity and bilateral symmetry not used"

    def _forward(self, wi: Parts, wo: Parts) -> Parts:
        (xi, yi, zi), (xo, yo, zo) = wi, wo
        theta_i, phi_i = polar(xi, yi, zi)
        theta_o, phi_o = polar(xo, yo, zo)
        return theta_i, phi_i, theta_o, phi_o

    def _inverse(self, c: Parts) -> tuple[Parts, BoolArray]:
        c0, c1, c2, c3 = c
        ok = theta_in_range(c0) & theta_in_range(c2)
        ti, to = clamp_theta(c0), clamp_theta(c2)
        si, so = np.sin(ti), np.sin(to)
        out = (si * np.cos(c1), si * np.sin(c1), np.cos(ti), so * np.cos(c3), so * np.sin(c3))
        return (*out, np.cos(to)), ok

    def _reduce(self, c: Parts) -> Parts:
        return c[0], c[2], wrap_two_pi_in_place(c[3] - c[1])
