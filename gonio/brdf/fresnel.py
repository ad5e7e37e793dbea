"""Fresnel reflectance of a smooth interface, as a function of cos θd.

Light arrives from a medium of index 1 (air) at angle θ to the interface normal
(for a microfacet model, the microfacet normal: θ = θd). With the relative index
η (real for a dielectric, η + iκ for a conductor) and g = η cos θt =
√(η² − sin² θ) (principal square root, Re g ≥ 0):

    r_s = (cos θ − g) / (cos θ + g),    r_p = (η² cos θ − g) / (η² cos θ + g),
    R_s = |r_s|²,  R_p = |r_p|²,  F = (R_s + R_p) / 2   (unpolarized light).

For a real η < 1 and sin θ > η, g is imaginary: total internal reflection, F = 1.
η = 1 is no interface: F = 0 (also at grazing incidence, where the formulas are
0/0). η² − sin²θ is computed as (η − 1)(η + 1) + cos²θ, exact at η = 1.
Schlick's approximation F ≈ F0 + (1 − F0)(1 − cos θ)⁵ is exact at normal
incidence and at grazing. All functions broadcast their arguments.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.brdf.base import Colour, ParamValue, colour
from gonio.errors import DomainError
from gonio.types import ArrayLike, FloatArray

#: Fresnel options of the microfacet models.
KINDS = ("none", "schlick", "dielectric", "conductor")


def _cos(cos_theta: ArrayLike) -> FloatArray:
    return np.clip(np.asarray(cos_theta, dtype=np.float64), 0.0, 1.0)


def schlick(cos_theta: ArrayLike, f0: ArrayLike) -> FloatArray:
    """Schlick's approximation F0 + (1 − F0)(1 − cos θ)⁵."""
    c = _cos(cos_theta)
    f = np.asarray(f0, dtype=np.float64)
    return np.asarray(f + (1.0 - f) * (1.0 - c) ** 5, dtype=np.float64)


def dielectric_sp(cos_theta: ArrayLike, eta: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """(R_s, R_p) of a dielectric of real relative index η > 0, in real arithmetic."""
    c = _cos(cos_theta)
    n = np.asarray(eta, dtype=np.float64)
    n2 = n * n
    g2 = (n - 1.0) * (n + 1.0) + c * c  # η² − sin²θ without cancellation at η ≈ 1
    tir = g2 < 0.0
    g = np.sqrt(np.maximum(g2, 0.0))
    den_s, den_p = c + g, n2 * c + g
    # den = 0: η = 1 at grazing (no interface), or η² cos θ underflowing under TIR.
    interface = n != 1.0
    ok_s, ok_p = (den_s > 0.0) & interface, (den_p > 0.0) & interface
    rs = np.where(ok_s, (c - g) / np.where(ok_s, den_s, 1.0), 0.0)
    rp = np.where(ok_p, (n2 * c - g) / np.where(ok_p, den_p, 1.0), 0.0)
    return np.where(tir, 1.0, rs * rs), np.where(tir, 1.0, rp * rp)


def dielectric(cos_theta: ArrayLike, eta: ArrayLike) -> FloatArray:
    """Unpolarized reflectance of a dielectric of real relative index η > 0."""
    rs, rp = dielectric_sp(cos_theta, eta)
    return np.asarray(0.5 * (rs + rp), dtype=np.float64)


def conductor_sp(
    cos_theta: ArrayLike, eta: ArrayLike, kappa: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """(R_s, R_p) for the complex relative index η + iκ (κ ≥ 0).

    g = u + iv is the complex principal root; |r|² are then formed in real arithmetic
    (|a ± g|² = (a ± u)² + (b ± v)² for a complex a = A + iB).
    """
    c = _cos(cos_theta)
    n = np.asarray(eta, dtype=np.float64)
    k = np.asarray(kappa, dtype=np.float64)
    m = n + 1j * k
    # principal root of m² − sin²θ: Re g ≥ 0, Im g ≥ 0 since Im m² ≥ 0
    g = np.sqrt((m - 1.0) * (m + 1.0) + c * c)
    u, v = g.real, g.imag
    a, b = (n - k) * (n + k) * c, 2.0 * n * k * c  # m² cos θ
    num_s, den_s = (c - u) ** 2 + v * v, (c + u) ** 2 + v * v
    num_p, den_p = (a - u) ** 2 + (b - v) ** 2, (a + u) ** 2 + (b + v) ** 2
    interface = (n != 1.0) | (k != 0.0)  # η + iκ = 1: no interface (and 0/0 at grazing)
    ok_s, ok_p = (den_s > 0.0) & interface, (den_p > 0.0) & interface
    return (
        np.asarray(np.where(ok_s, num_s / np.where(ok_s, den_s, 1.0), 0.0), dtype=np.float64),
        np.asarray(np.where(ok_p, num_p / np.where(ok_p, den_p, 1.0), 0.0), dtype=np.float64),
    )


def conductor(cos_theta: ArrayLike, eta: ArrayLike, kappa: ArrayLike) -> FloatArray:
    """Unpolarized reflectance for the complex relative index η + iκ (κ ≥ 0)."""
    rs, rp = conductor_sp(cos_theta, eta, kappa)
    return np.asarray(0.5 * (rs + rp), dtype=np.float64)


@dataclass(frozen=True)
class Fresnel:
    """A Fresnel option of a microfacet model with its (grey or RGB) parameters."""

    kind: str
    f0: Colour | None = None
    ior: Colour | None = None
    k: Colour | None = None

    def params(self) -> dict[str, ParamValue]:
        """The option as model parameters (``fresnel`` plus the ones it uses)."""
        out: dict[str, ParamValue] = {"fresnel": self.kind}
        for key in ("f0", "ior", "k"):
            value = getattr(self, key)
            if value is not None:
                out[key] = value
        return out

    @property
    def is_rgb(self) -> bool:
        return any(isinstance(v, tuple) for v in (self.f0, self.ior, self.k))

    def __call__(self, cos_theta_d: FloatArray) -> FloatArray:
        """F at cos θd; give ``cos_theta_d`` a trailing axis of 1 when `is_rgb`."""
        if self.kind == "schlick":
            return schlick(cos_theta_d, np.asarray(self.f0))
        if self.kind == "dielectric":
            return dielectric(cos_theta_d, np.asarray(self.ior))
        if self.kind == "conductor":
            return conductor(cos_theta_d, np.asarray(self.ior), np.asarray(self.k))
        return np.ones_like(cos_theta_d)


#: The largest ``ior`` and ``k`` accepted: no optical material comes near (metals in the
#: far infrared reach ~100), and it keeps (η + iκ)² and its squares finite in float64.
MAX_INDEX = 1000.0


def make_fresnel(kind: str, f0: object = None, ior: object = None, k: object = None) -> Fresnel:
    """Check a Fresnel option and its parameters.

    ``none``: F = 1. ``schlick``: needs nothing else, ``f0`` ∈ [0, 1] (default 0.04).
    ``dielectric``: ``ior`` > 0 (default 1.5). ``conductor``: ``ior`` > 0 and ``k`` ≥ 0,
    both required; each at most `MAX_INDEX`. Each may be RGB. A parameter the option
    does not use is an error.
    """
    used = {"none": (), "schlick": ("f0",), "dielectric": ("ior",), "conductor": ("ior", "k")}
    if kind not in used:
        raise DomainError(f"unknown fresnel {kind!r}; expected one of {', '.join(KINDS)}")
    given = {"f0": f0, "ior": ior, "k": k}
    extra = [name for name, v in given.items() if v is not None and name not in used[kind]]
    if extra:
        raise DomainError(f"fresnel={kind!r} does not take {', '.join(extra)}")
    if kind == "schlick":
        value = colour("f0", 0.04 if f0 is None else f0, low=0.0)
        if max(np.atleast_1d(value)) > 1.0:
            raise DomainError(f"parameter f0 must lie in [0, 1], got {value}")
        return Fresnel(kind, f0=value)
    if kind == "dielectric":
        given_ior = 1.5 if ior is None else ior
        return Fresnel(kind, ior=colour("ior", given_ior, low=0.0, low_open=True, high=MAX_INDEX))
    if kind == "conductor":
        if ior is None or k is None:
            raise DomainError("fresnel='conductor' needs both ior and k")
        return Fresnel(
            kind,
            ior=colour("ior", ior, low=0.0, low_open=True, high=MAX_INDEX),
            k=colour("k", k, low=0.0, high=MAX_INDEX),
        )
    return Fresnel(kind)
