"""Lambert and the cosine-lobe models: Phong, Blinn-Phong and the family of
Romanyuk et al.'s modified cosine-quadratic model.

    lambert             f = ρ / π
    phong               f = ks (n + 2)/(2π) cos^n ψ + kd/π,     cos ψ = r · wo
    blinn_phong         f = ks C(n) cos^n θh + kd/π
    cosine_quadratic    f = ks C(n) (ξ n (cos θh − 1) + 1)² + kd/π,   ξ = 1/2
    cosine_quadratic_modified   the same with ξ from Romanyuk et al.'s eq. 12 (≈ 0.4629)
    schlick_lobe        f = ks C(n) cos θh / (n − n cos θh + cos θh) + kd/π

with r = 2 (wi · n) n − wi the mirror direction of wi and θh the angle between
the normal and the halfway vector. Both lobes are 0 where their cosine is < 0.

Normalizations (derivations in docs/explanations/brdf.md). Phong's (n + 2)/(2π) makes the
lobe's directional albedo exactly 1 at normal incidence, its maximum over θi.
Blinn-Phong's

    C(n) = (n + 2)(n + 4) / (8π (n + 2^(−n/2)))

does the same for cos^n θh (the closed form of the albedo at normal incidence;
the maximum over θi, measured). The popular (n + 8)/(8π) is too large for every
n > 0 (albedo up to 1.075 at n = 8). Romanyuk et al.'s lobes approximate cos^n θh and
share C(n); their albedo is not held to 1 (the cosine-quadratic lobes cut at
their zero, ξ n (cos θh − 1) + 1 = 0). With ks + kd ≤ 1, phong and blinn_phong
conserve energy. Every model here is reciprocal (cos ψ is symmetric in wi, wo)
and isotropic. Colour parameters: ρ (``albedo``), ``ks``, ``kd``.
"""

from __future__ import annotations

import numpy as np

from gonio.brdf import lobes
from gonio.brdf.base import BRDF, ParamValue, colour, scalar
from gonio.brdf.geometry import Pair
from gonio.errors import DomainError
from gonio.types import ArrayLike, FloatArray

#: Largest shininess accepted (a lobe half-width at half maximum of ~1.2e-4 rad).
N_MAX = 1e8


def blinn_normalization(n: ArrayLike) -> FloatArray:
    """C(n) = (n + 2)(n + 4) / (8π (n + 2^(−n/2))) in sr⁻¹.

    ∫ C(n) cos^n θh cos θo dωo = 1 for wi = n (normal incidence).
    """
    nn = np.asarray(n, dtype=np.float64)
    return np.asarray((nn + 2.0) * (nn + 4.0) / (8.0 * np.pi * (nn + 2.0 ** (-nn / 2.0))))


def phong_normalization(n: ArrayLike) -> FloatArray:
    """(n + 2) / (2π), in sr⁻¹: ∫ cos^n ψ cos θo dωo = 2π / (n + 2) at wi = n."""
    return np.asarray((np.asarray(n, dtype=np.float64) + 2.0) / (2.0 * np.pi))


class Lambert(BRDF):
    """f = ρ/π; ``albedo`` ρ ≥ 0 (energy conserving for ρ ≤ 1)."""

    name = "lambert"
    physically_based = True
    colour_params = ("albedo",)

    def __init__(self, albedo: object) -> None:
        super().__init__({"albedo": colour("albedo", albedo, low=0.0)})

    def _eval(self, p: Pair) -> FloatArray:
        return self.colour("albedo") / np.pi


class _CosineLobe(BRDF):
    """ks · norm(n) · lobe(cos) + kd/π, with shininess n ≥ 0 and weights ks, kd ≥ 0."""

    colour_params = ("ks", "kd")

    def __init__(self, n: object, ks: object, kd: object, **extra: ParamValue) -> None:
        self.n = scalar("n", n, low=0.0, high=N_MAX)
        super().__init__(
            {"n": self.n, "ks": colour("ks", ks, low=0.0), "kd": colour("kd", kd, low=0.0), **extra}
        )

    def _cos(self, p: Pair) -> FloatArray:
        raise NotImplementedError

    def _norm(self) -> float:
        raise NotImplementedError

    def _lobe(self, c: FloatArray) -> FloatArray:
        return lobes.power_cosine(c, self.n)

    def _eval(self, p: Pair) -> FloatArray:
        c = self._cos(p)
        lobe = np.where(c < 0.0, 0.0, self._lobe(c))  # also for n = 0, where 0⁰ = 1
        spec = self.spread(self._norm() * lobe) * self.colour("ks")
        return np.asarray(spec + self.colour("kd") / np.pi, dtype=np.float64)


class Phong(_CosineLobe):
    """Energy-normalized Phong, ks (n + 2)/(2π) cos^n ψ + kd/π (reciprocal as written)."""

    name = "phong"
    physically_based = True

    def __init__(self, n: object, ks: object = 1.0, kd: object = 0.0) -> None:
        super().__init__(n, ks, kd)

    def _cos(self, p: Pair) -> FloatArray:
        return p.cos_psi()

    def _norm(self) -> float:
        return float(phong_normalization(self.n))


class BlinnPhong(_CosineLobe):
    """Energy-normalized Blinn-Phong, ks C(n) cos^n θh + kd/π."""

    name = "blinn_phong"
    physically_based = True

    def __init__(self, n: object, ks: object = 1.0, kd: object = 0.0) -> None:
        super().__init__(n, ks, kd)

    def _cos(self, p: Pair) -> FloatArray:
        return p.cos_theta_h()

    def _norm(self) -> float:
        return float(blinn_normalization(self.n))


class CosineQuadratic(BlinnPhong):
    """Romanyuk et al.'s F_2: `BlinnPhong` with (n (cos θh − 1)/2 + 1)² for cos^n θh.

    The lobe is cut at 0 beyond its zero crossing.
    """

    name = "cosine_quadratic"
    physically_based = False

    def _lobe(self, c: FloatArray) -> FloatArray:
        return lobes.cosine_quadratic(c, self.n, lobes.XI_STANDARD)


class CosineQuadraticModified(BlinnPhong):
    """Romanyuk et al.'s F_VOL: (ξ n (cos θh − 1) + 1)², zeroed beyond its zero crossing.

    ``xi``: "eq12" (default, ξ ≈ 0.4629 solving Romanyuk et al.'s eq. 12), "29/64", or a
    number in (0, 1].
    """

    name = "cosine_quadratic_modified"
    physically_based = False

    def __init__(self, n: object, ks: object = 1.0, kd: object = 0.0, xi: object = "eq12") -> None:
        stored: ParamValue
        if xi == "eq12":
            value, stored = lobes.xi_equation_12(), "eq12"
        elif xi == "29/64":
            value, stored = lobes.XI_29_64, "29/64"
        elif isinstance(xi, str):
            raise DomainError(f"parameter xi must be 'eq12', '29/64' or a number, got {xi!r}")
        else:
            value = stored = scalar("xi", xi, low=0.0, low_open=True, high=1.0)
        _CosineLobe.__init__(self, n, ks, kd, xi=stored)
        self.xi = float(value)

    def _lobe(self, c: FloatArray) -> FloatArray:
        return lobes.cosine_quadratic(c, self.n, self.xi)


class SchlickLobe(BlinnPhong):
    """Romanyuk et al.'s F_S (eq. 4): cos θh / (n − n cos θh + cos θh) for cos^n θh."""

    name = "schlick_lobe"
    physically_based = False

    def _lobe(self, c: FloatArray) -> FloatArray:
        # cos θh = 0 only for two grazing directions; keep n = 0 there away from 0/0.
        positive = c > 0.0
        return np.where(positive, lobes.schlick(np.where(positive, c, 1.0), self.n), 0.0)
