"""The errors of Romanyuk et al.'s modified cosine-quadratic lobes against cos^n ψ,
recomputed with gonio's own lobes (`gonio.brdf.lobes`).

Conventions: c = cos ψ, n the shininess; the "epicentre zone" is ψ ≤ lim(n) =
acos(exp(−K/n)) with the paper's printed K = 0.511. The relative error of a lobe F
against F_B = cos^n ψ is δ = |F − F_B| / F_B, the absolute error Δ = |F − F_B| (F_B
peaks at 1, so Δ is a fraction of the peak). All angles in radians.

Equations 11/12: with c = cos ψ the inner integrals are polynomials in c, so for each n

    ∫_0^lim cos^n ψ cos ψ sin ψ dψ = (1 − c0^(n+2)) / (n + 2),           c0 = e^(−K/n)
    ∫_0^lim (ξ n (cos ψ − 1) + 1)² cos ψ sin ψ dψ = A ξ² + B ξ + C,       u = 1 − c0
    A = n² (u³/3 − u⁴/4),  B = −2 n (u²/2 − u³/3),  C = u − u²/2

(exact, evaluated with expm1), and the outer integral over n ∈ [16, 256] is done
with ``scipy.integrate.quad`` (relative tolerance 1e-13; error estimates ≲ 2e-14).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize

from gonio.brdf import lobes
from gonio.types import ArrayLike, FloatArray

K_PRINTED = 0.511  # the paper's lim(n) = acos(exp(−0.511/n))
K_LN_5_3 = math.log(5.0 / 3.0)  # 0.51083: F_B = 3/5 at the limit; reproduces eq 12's digits
EQ11_N = (16.0, 256.0)
FIG3_N = (16.0, 1000.0)
SEED_XI = 0.463
SEED_DELTA_VOL = 0.019  # "the maximum δ of F_VOL ... has the value 1.9%"
SEED_IMPROVEMENT = 4.5  # "a 4.5-fold improvement"


@dataclass(frozen=True)
class Eq12:
    """Equation 12 as ``left = quadratic ξ² + linear ξ + constant`` (2π dropped both sides)."""

    left: float
    quadratic: float
    linear: float
    constant: float
    abserr: float = 0.0  # largest quad error estimate of the four numbers

    def xi(self) -> float:
        """The root of the quadratic in (0, 1) (the other one, ≈ 5.45, is no lobe)."""
        a, b, c = self.quadratic, self.linear, self.constant - self.left
        return (-b - math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


SEED_EQ12 = Eq12(left=1.098, quadratic=0.12026, linear=-0.71068, constant=1.40119)


def inner_integrals(
    n: ArrayLike, k: float = K_PRINTED
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per-n inner integrals of eq 11 over ψ ∈ [0, acos(e^(−k/n))]: (left, A, B, C)."""
    nn = np.asarray(n, dtype=np.float64)
    u = -np.expm1(-k / nn)
    left = -np.expm1(-k * (nn + 2.0) / nn) / (nn + 2.0)
    a = nn * nn * u**3 * (1.0 / 3.0 - u / 4.0)
    b = -2.0 * nn * u**2 * (0.5 - u / 3.0)
    c = u * (1.0 - u / 2.0)
    return left, a, b, c


def equation_12(k: float = K_PRINTED, n_range: tuple[float, float] = EQ11_N) -> Eq12:
    """Eq 12's four numbers from eq 11: integrals over n of :func:`inner_integrals`."""
    values: list[float] = []
    errors: list[float] = []
    for i in range(4):
        v, e = integrate.quad(
            lambda n, i=i: float(inner_integrals(n, k)[i]), *n_range, epsabs=0.0, epsrel=1e-13
        )
        values.append(float(v))
        errors.append(float(e))
    left, quadratic, linear, constant = values
    return Eq12(left, quadratic, linear, constant, abserr=max(errors))


@dataclass(frozen=True)
class Lobe:
    """A study lobe: cosine-quadratic with ``xi`` (cut at its zero) or Schlick (xi None)."""

    name: str
    xi: float | None

    def __call__(self, cos_psi: ArrayLike, n: ArrayLike) -> FloatArray:
        if self.xi is None:
            return lobes.schlick(cos_psi, n)
        return lobes.cosine_quadratic(cos_psi, n, self.xi)


def study_lobes() -> tuple[Lobe, ...]:
    """F_VOL with the paper's ξ = 0.463, with the recomputed eq-12 root and 29/64; F_2; F_S."""
    return (
        Lobe("F_VOL(0.463)", SEED_XI),
        Lobe("F_VOL(eq12)", equation_12().xi()),
        Lobe("F_VOL(29/64)", lobes.XI_29_64),
        Lobe("F_2", lobes.XI_STANDARD),
        Lobe("F_S", None),
    )


def epicentre_max_relative_error(
    lobe: Lobe, n: ArrayLike, k: float = K_PRINTED
) -> tuple[FloatArray, FloatArray]:
    """Exact max over ψ ≤ lim(n) of δ, and the cos ψ where it occurs (n > 2).

    ln(F/F_B) vanishes at c = 1 and has one stationary point: for the quadratic lobe
    2ξ c = ξ n (c − 1) + 1, i.e. c* = (ξ n − 1) / (ξ (n − 2)) (≤ 1 iff ξ ≤ 1/2); for
    Schlick none inside (0, 1). So the max is at the zone's edge c0 or at c*.
    """
    nn = np.asarray(n, dtype=np.float64)
    c0 = np.exp(-k / nn)
    cands = [c0]
    if lobe.xi is not None:
        cands.append(np.clip((lobe.xi * nn - 1.0) / (lobe.xi * (nn - 2.0)), c0, 1.0))
    c = np.stack(np.broadcast_arrays(*cands))
    delta = np.abs(lobe(c, nn) / lobes.power_cosine(c, nn) - 1.0)
    i = np.argmax(delta, axis=0)[None]
    return np.take_along_axis(delta, i, 0)[0], np.take_along_axis(c, i, 0)[0]


def epicentre_limit_n_inf(lobe: Lobe, k: float = K_PRINTED) -> float:
    """lim_{n→∞} of the epicentre max δ (x = n(1 − cos ψ) ∈ [0, k], F_B → e^(−x))."""
    if lobe.xi is None:
        return math.exp(k) / (1.0 + k) - 1.0
    xi = lobe.xi
    edge = abs((1.0 - xi * k) ** 2 * math.exp(k) - 1.0)
    x_star = (1.0 - 2.0 * xi) / xi
    inner = abs(4.0 * xi * xi * math.exp(x_star) - 1.0) if 0.0 <= x_star <= k else 0.0
    return max(edge, inner)


def max_over_n(
    curve: Callable[[FloatArray], FloatArray],
    n_range: tuple[float, float] = FIG3_N,
    points: int = 1025,
) -> tuple[float, float]:
    """(max, argmax) of a smooth curve over n: geometric grid then bounded Brent."""
    n = np.geomspace(*n_range, points)
    v = curve(n)
    i = int(np.argmax(v))
    best, at = float(v[i]), float(n[i])
    lo, hi = float(n[max(i - 1, 0)]), float(n[min(i + 1, points - 1)])
    res = optimize.minimize_scalar(
        lambda x: -float(curve(np.array([x]))[0]),
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-9 * hi},
    )
    if -float(res.fun) > best:
        best, at = -float(res.fun), float(res.x)
    return best, at


def epicentre_peak(lobe: Lobe, n_range: tuple[float, float] = FIG3_N) -> tuple[float, float]:
    """Max over n ∈ n_range of the epicentre max δ, and the n where it occurs."""

    def curve(n: FloatArray) -> FloatArray:
        return epicentre_max_relative_error(lobe, n)[0]

    return max_over_n(curve, n_range)


def improvement_ratios(
    vol: Lobe, others: tuple[Lobe, ...], n_range: tuple[float, float] = FIG3_N
) -> list[tuple[str, float]]:
    """Candidate readings of the "4.5-fold" claim for one F_VOL, named."""

    def peak(lobe: Lobe) -> float:
        return epicentre_peak(lobe, n_range)[0]

    def at(lobe: Lobe, n: float) -> float:
        return float(epicentre_max_relative_error(lobe, n)[0])

    out: list[tuple[str, float]] = []
    n0 = n_range[0]
    for o in others:
        out.append((f"max δ {o.name} / max δ {vol.name}", peak(o) / peak(vol)))
        out.append((f"δ {o.name} / δ {vol.name} at n={n0:g}", at(o, n0) / at(vol, n0)))
        out.append((f"max δ {o.name} / the paper's 1.9%", peak(o) / SEED_DELTA_VOL))
    return out


def eq14_psi(n: ArrayLike) -> FloatArray:
    """Eq 14 of Romanyuk et al. as printed: acos((29 n − 64) / (29 n))."""
    nn = np.asarray(n, dtype=np.float64)
    return np.asarray(np.arccos((29.0 * nn - 64.0) / (29.0 * nn)), dtype=np.float64)


def inflexion_psi(n: ArrayLike) -> FloatArray:
    """Exact inflexion of cos^n ψ (n > 1): (cos^n)'' = n cos^(n−2) ((n−1) sin² − cos²) = 0."""
    nn = np.asarray(n, dtype=np.float64)
    return np.asarray(np.arctan(1.0 / np.sqrt(nn - 1.0)), dtype=np.float64)


def k_at_inflexion(n: ArrayLike) -> FloatArray:
    """The K making exp(−K/n) the exact inflexion cos ψ: −(n/2) ln(1 − 1/n) → 1/2."""
    nn = np.asarray(n, dtype=np.float64)
    return np.asarray(-0.5 * nn * np.log1p(-1.0 / nn), dtype=np.float64)


def n_where_limit_is_inflexion(k: float = K_PRINTED) -> float:
    """The n at which acos(exp(−k/n)) equals the exact inflexion point."""
    return float(optimize.brentq(lambda n: float(k_at_inflexion(n)) - k, 1.5, 1e6, xtol=1e-12))


def minimax_xi(n_range: tuple[float, float] = FIG3_N) -> tuple[float, float]:
    """ξ minimizing max over n and the epicentre zone of δ, and that minimal max δ."""
    n = np.geomspace(*n_range, 513)

    def worst(xi: float) -> float:
        return float(np.max(epicentre_max_relative_error(Lobe("", xi), n)[0]))

    res = optimize.minimize_scalar(
        worst, bounds=(0.40, 0.50), method="bounded", options={"xatol": 1e-8}
    )
    return float(res.x), float(res.fun)


def render_summary() -> str:
    """Compact fixed-width table of the check of Romanyuk et al. (for ``make demo``)."""
    seed, ours, ln53 = SEED_EQ12, equation_12(), equation_12(K_LN_5_3)
    lines = [
        "Romanyuk et al.'s lobes vs F_B = cos^n ψ (K = 0.511; δ relative, epicentre zone)",
        f"{'eq 12':<14}{'left':>10}{'ξ²':>10}{'ξ':>10}{'1':>10}{'root ξ':>10}",
    ]
    for name, e in (("seed printed", seed), ("ours K=0.511", ours), ("ours K=ln5/3", ln53)):
        lines.append(
            f"{name:<14}{e.left:>10.5f}{e.quadratic:>10.5f}{e.linear:>10.5f}"
            f"{e.constant:>10.5f}{e.xi():>10.5f}"
        )
    xi_mm, d_mm = minimax_xi()
    lines.append(
        f"29/64 = {lobes.XI_29_64:.6f}; minimax-δ ξ on n∈[16,1000] = {xi_mm:.5f}"
        f" (max δ {100 * d_mm:.2f}%)"
    )
    lines.append(f"{'lobe':<14}{'δ n=16':>9}{'max δ':>9}{'at n':>7}{'n→∞':>9}")
    ls = study_lobes()
    for lobe in ls:
        d16 = float(epicentre_max_relative_error(lobe, 16.0)[0])
        dmax, nmax = epicentre_peak(lobe)
        lines.append(
            f"{lobe.name:<14}{100 * d16:>8.2f}%{100 * dmax:>8.2f}%{nmax:>7.0f}"
            f"{100 * epicentre_limit_n_inf(lobe):>8.2f}%"
        )
    lines.append("improvement ratios (seed: 4.5-fold, 1.9%):")
    for name, r in improvement_ratios(ls[0], ls[3:]):
        lines.append(f"  {name:<40}{r:>6.2f}")
    n = np.geomspace(16.0, 1000.0, 64)
    resid = float(np.max(lobes.cosine_quadratic(np.cos(eq14_psi(n)), n, lobes.XI_29_64, False)))
    lines.append(
        f"eq 14 zero of F_VOL(29/64): max F there {resid:.1e}; F_VOL(0.463) raw there "
        f"{(1 - SEED_XI * 64 / 29) ** 2:.1e}"
    )
    lines.append(
        f"lim(n) = inflexion at n = {n_where_limit_is_inflexion():.1f}; "
        f"lim/inflexion − 1 at n=16, 1000: "
        + ", ".join(
            f"{100 * (math.acos(math.exp(-K_PRINTED / m)) / float(inflexion_psi(m)) - 1):+.2f}%"
            for m in (16.0, 1000.0)
        )
    )
    return "\n".join(lines)
