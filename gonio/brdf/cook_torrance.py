"""Microfacet (Cook-Torrance) models with Smith height-correlated masking-shadowing.

    f(wi, wo) = D(h) F(cos θd) G2(wi, wo) / (4 cos θi cos θo) + kd/π
              = D(h) F(cos θd) V(wi, wo) + kd/π,

h the halfway direction, θd the angle between wi and h, D and V from
`gonio.brdf.microfacet` (V in a form that stays finite at grazing), F from
`gonio.brdf.fresnel`. f = 0 where either direction is exactly grazing (G2 = 0
there); note that the limit of f as θi → 90° at fixed wo is finite and non-zero,
only f cos θi tends to 0.

``cook_torrance(alpha, distribution="ggx"|"beckmann", fresnel=..., kd=0)`` and
``ggx_anisotropic(alpha_x, alpha_y, fresnel=..., kd=0)`` (αx along the sample's x
axis). Fresnel options and their parameters: see `gonio.brdf.fresnel.make_fresnel`.
Roughness α ∈ [1e-6, 1e3], which keeps every intermediate in float64's normal
range. The specular part conserves energy (single scattering, F ≤ 1: albedo ≤ 1);
kd/π adds to it, so the total conserves energy when kd ≤ 1 − max albedo of the
specular part. Reciprocal; isotropic except anisotropic GGX with αx ≠ αy.
"""

from __future__ import annotations

import numpy as np

from gonio.brdf import microfacet as mf
from gonio.brdf.base import BRDF, ParamValue, colour, scalar
from gonio.brdf.fresnel import make_fresnel
from gonio.brdf.geometry import Pair
from gonio.errors import DomainError
from gonio.types import FloatArray

ALPHA_MIN, ALPHA_MAX = 1e-6, 1e3
DISTRIBUTIONS = ("ggx", "beckmann")


def _alpha(name: str, value: object) -> float:
    return scalar(name, value, low=ALPHA_MIN, high=ALPHA_MAX)


class _Microfacet(BRDF):
    """D F V + kd/π; subclasses give D(h) and B(w) = cos θ (½ + Λ(w))."""

    physically_based = True
    colour_params = ("f0", "ior", "k", "kd")

    def __init__(
        self,
        shape: dict[str, ParamValue],
        fresnel: object,
        f0: object,
        ior: object,
        k: object,
        kd: object,
    ) -> None:
        if not isinstance(fresnel, str):
            raise DomainError(f"parameter fresnel must be a name, got {fresnel!r}")
        self.fresnel = make_fresnel(fresnel, f0=f0, ior=ior, k=k)
        super().__init__({**shape, **self.fresnel.params(), "kd": colour("kd", kd, low=0.0)})

    def _d(self, hx: FloatArray, hy: FloatArray, hz: FloatArray) -> FloatArray:
        raise NotImplementedError

    def _b(self, x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
        raise NotImplementedError

    def _eval(self, p: Pair) -> FloatArray:
        d = self._d(*p.halfway())
        v = mf.visibility(self._b(p.xi, p.yi, p.ci), self._b(p.xo, p.yo, p.co), p.ci, p.co)
        f = self.fresnel(self.spread(p.cos_theta_d()))
        return np.asarray(self.spread(d * v) * f + self.colour("kd") / np.pi, dtype=np.float64)


class CookTorrance(_Microfacet):
    """Isotropic microfacet BRDF with a GGX or Beckmann distribution of roughness α."""

    name = "cook_torrance"

    def __init__(
        self,
        alpha: object,
        distribution: object = "ggx",
        fresnel: object = "schlick",
        f0: object = None,
        ior: object = None,
        k: object = None,
        kd: object = 0.0,
    ) -> None:
        if distribution not in DISTRIBUTIONS:
            raise DomainError(
                f"unknown distribution {distribution!r}; expected one of {', '.join(DISTRIBUTIONS)}"
            )
        self.alpha = _alpha("alpha", alpha)
        self.distribution = str(distribution)
        shape: dict[str, ParamValue] = {"alpha": self.alpha, "distribution": self.distribution}
        super().__init__(shape, fresnel, f0, ior, k, kd)

    def _d(self, hx: FloatArray, hy: FloatArray, hz: FloatArray) -> FloatArray:
        if self.distribution == "ggx":
            return mf.ggx_d(hx, hy, hz, self.alpha)
        return mf.beckmann_d(hx, hy, hz, self.alpha)

    def _b(self, x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
        if self.distribution == "ggx":
            return mf.ggx_b(x, y, z, self.alpha)
        return mf.beckmann_b(x, y, z, self.alpha)


class GGXAnisotropic(_Microfacet):
    """GGX with roughness αx along the sample's x axis and αy along y."""

    name = "ggx_anisotropic"

    def __init__(
        self,
        alpha_x: object,
        alpha_y: object,
        fresnel: object = "schlick",
        f0: object = None,
        ior: object = None,
        k: object = None,
        kd: object = 0.0,
    ) -> None:
        self.alpha_x = _alpha("alpha_x", alpha_x)
        self.alpha_y = _alpha("alpha_y", alpha_y)
        shape: dict[str, ParamValue] = {"alpha_x": self.alpha_x, "alpha_y": self.alpha_y}
        super().__init__(shape, fresnel, f0, ior, k, kd)

    @property
    def isotropic(self) -> bool:
        return self.alpha_x == self.alpha_y

    def _d(self, hx: FloatArray, hy: FloatArray, hz: FloatArray) -> FloatArray:
        return mf.ggx_aniso_d(hx, hy, hz, self.alpha_x, self.alpha_y)

    def _b(self, x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
        return mf.ggx_aniso_b(x, y, z, self.alpha_x, self.alpha_y)
