"""The specular lobe's cross-section flattens as the incidence angle grows (a 2025 derivation).

The derivation (in Chinese and English) shows why a microfacet lobe becomes
anisotropic as the view angle grows; this module measures its claim on full models.

Geometry. wi = (sin θ, 0, cos θ), mirror direction m = (−sin θ, 0, cos θ). Two
great circles cross at m, perpendicular to it: the in-plane one, wo(s) = cos s m +
sin s (cos θ, 0, sin θ) (s > 0 toward the normal, s < 0 toward the horizon, which
it meets at s = −(π/2 − θ)), and the perpendicular one, wo(s) = cos s m + sin s ŷ.
The lobe is g(wo) = f(wi, wo) cos θo (default) or f(wi, wo). Its half-widths are
the first |s| where g falls to half of its in-plane maximum, found by a scan and
bisection (to ~1e-13 rad); aspect = larger / smaller of the in-plane width
(up + down) and the perpendicular width (2 · perp).

Why f cos θo: with F = G2 = 1, f cos θo = D(h)/(4 cos θi), so its level sets are
exactly the images of the cones θh = const of microfacet normals, the seed's own
construction; only F, G2 and the horizon make the full model depart from it. The
BRDF f itself carries an extra 1/cos θo that pulls the lobe toward the horizon.

Seed construction: the cone of normals at θh = a, a = the half-maximum angle of
D, reflected about wi: {wo : θh(wi, wo) = a}. Its widths along the same axes come
from the same root finding on θh (ignoring the horizon). The seed's own algebra
gives the semi-axes in closed form: 2a in-plane (its L_min = −sin²a, independent
of θ) and δ, sin(δ/2) = sin a cos θ, for the closest approach (its
L_max = −sin²a cos²θ): `seed_closed_form_aspect` = 2a/δ ≈ 1/cos θ.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gonio.brdf import BRDF, create
from gonio.brdf import microfacet as mf
from gonio.errors import DomainError
from gonio.types import ArrayLike, BoolArray, FloatArray

WEIGHTS = ("f_cos", "f")
_BISECTIONS = 60


@dataclass(frozen=True)
class LobeWidths:
    """Half-widths (radians) of a lobe about the mirror direction, per incidence angle.

    ``up`` / ``down``: in the plane of incidence toward the normal / the horizon;
    ``perp``: perpendicular to it; ``peak``: in-plane position of the maximum
    (radians, > 0 toward the normal). ``peak_at_horizon``: the in-plane maximum
    is at the horizon (then the lobe has no half-maximum width: NaN). A half-axis
    along which the lobe never falls to half its peak is NaN too.
    """

    theta_i: FloatArray
    up: FloatArray
    down: FloatArray
    perp: FloatArray
    peak: FloatArray
    peak_at_horizon: BoolArray

    @property
    def aspect(self) -> FloatArray:
        """Larger over smaller of the in-plane and perpendicular full widths."""
        a, b = self.up + self.down, 2.0 * self.perp
        return np.asarray(np.maximum(a, b) / np.minimum(a, b), dtype=np.float64)


def _axes(theta: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """wi, m and the unit tangents (up, perp) at m, each (K, 3)."""
    s, c, z = np.sin(theta), np.cos(theta), np.zeros_like(theta)
    wi = np.stack([s, z, c], -1)
    m = np.stack([-s, z, c], -1)
    up = np.stack([c, z, s], -1)
    perp = np.stack([z, np.ones_like(theta), z], -1)
    return wi, m, up, perp


def _along(m: FloatArray, e: FloatArray, s: FloatArray) -> FloatArray:
    """Directions cos s · m + sin s · e; m, e (K, 3), s (K, N) → (K, N, 3)."""
    return np.cos(s)[..., None] * m[:, None, :] + np.sin(s)[..., None] * e[:, None, :]


def _first_drop(
    g: FloatArray, s: FloatArray, level: FloatArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Bracket [lo, hi] of the first s where g (K, N) drops below level (K,); found flag."""
    below = g < level[:, None]
    found = below.any(axis=1)
    k = np.where(found, np.argmax(below, axis=1), g.shape[1] - 1)
    k = np.maximum(k, 1)
    rows = np.arange(g.shape[0])
    return (
        np.asarray(s[rows, k - 1], dtype=np.float64),
        np.asarray(s[rows, k], dtype=np.float64),
        np.asarray(found, dtype=bool),
    )


def _bisect(func: Callable[[FloatArray], FloatArray], lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Vectorized bisection for func(s) ≥ 0 at lo, < 0 at hi."""
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        ok = func(mid) >= 0.0
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.asarray(0.5 * (lo + hi), dtype=np.float64)


def lobe_widths(
    model: BRDF, theta_i: ArrayLike, *, weight: str = "f_cos", n_scan: int = 4096
) -> LobeWidths:
    """Half-maximum half-widths of ``model``'s lobe for wi at each θi (radians, < π/2)."""
    if weight not in WEIGHTS:
        raise DomainError(f"unknown weight {weight!r}; expected one of {', '.join(WEIGHTS)}")
    if model.is_rgb:
        raise DomainError("lobe widths need a grey model")
    theta = np.atleast_1d(np.asarray(theta_i, dtype=np.float64))
    wi, m, up, perp = _axes(theta)
    wi3 = wi[:, None, :]

    def g(e: FloatArray, s: FloatArray) -> FloatArray:
        wo = _along(m, e, s)
        value = model.eval(wi3, wo)
        return value * np.maximum(wo[..., 2], 0.0) if weight == "f_cos" else value

    u = np.linspace(0.0, 1.0, n_scan + 1)[None, :]
    limits = {
        "up": np.pi / 2 + theta,
        "down": np.pi / 2 - theta,
        "perp": np.full_like(theta, np.pi / 2),
    }
    dirs = {"up": up, "down": -up, "perp": perp}
    grids = {k: limits[k][:, None] * u for k in dirs}
    values = {k: g(dirs[k], grids[k]) for k in dirs}

    # In-plane maximum (refined by a parabola through the best sample and its neighbours).
    line = np.concatenate([values["down"][:, :0:-1], values["up"]], axis=1)
    pos = np.concatenate([-grids["down"][:, :0:-1], grids["up"]], axis=1)
    rows = np.arange(theta.size)
    k = np.clip(np.argmax(line, axis=1), 1, line.shape[1] - 2)
    y0, y1, y2 = line[rows, k - 1], line[rows, k], line[rows, k + 1]
    curv = y0 - 2.0 * y1 + y2
    shift = np.where(curv < 0.0, 0.5 * (y0 - y2) / np.where(curv < 0.0, curv, -1.0), 0.0)
    step = pos[rows, k + 1] - pos[rows, k]
    peak_pos = pos[rows, k] + np.clip(shift, -1.0, 1.0) * step
    peak_val = np.max(line, axis=1)
    half = 0.5 * peak_val

    # line[:, 0] lies on the horizon (g = 0 there by convention): a maximum next to it
    # means g grows all the way down to the horizon.
    at_horizon = np.argmax(line, axis=1) <= 1

    def excess(e: FloatArray) -> Callable[[FloatArray], FloatArray]:
        return lambda s: g(e, s[:, None])[:, 0] - half

    widths = {}
    for key, e in dirs.items():
        lo, hi, found = _first_drop(values[key], grids[key], half)
        widths[key] = np.where(at_horizon | ~found, np.nan, _bisect(excess(e), lo, hi))
    peak_pos = np.where(at_horizon, -limits["down"], peak_pos)
    return LobeWidths(theta, widths["up"], widths["down"], widths["perp"], peak_pos, at_horizon)


def lobe_aspect_ratio(model: BRDF, theta_i: ArrayLike, *, weight: str = "f_cos") -> FloatArray:
    """Aspect ratio (≥ 1) of ``model``'s lobe cross-section at each θi; see `lobe_widths`."""
    return lobe_widths(model, theta_i, weight=weight).aspect


def half_max_angle(distribution: str, alpha: float) -> float:
    """θ (radians) where D(θ) = D(0)/2 for an isotropic GGX or Beckmann D (α < 1)."""
    d = {"ggx": mf.ggx_d, "beckmann": mf.beckmann_d}[distribution]

    def ratio(t: FloatArray) -> FloatArray:
        return (
            d(np.sin(t), np.zeros_like(t), np.cos(t), alpha)
            / d(np.zeros(1), np.zeros(1), np.ones(1), alpha)
            - 0.5
        )

    lo, hi = np.zeros(1), np.full(1, np.pi / 2)
    return float(_bisect(ratio, lo, hi)[0])


def seed_cone_widths(theta_i: ArrayLike, cone_half_angle: float) -> LobeWidths:
    """Widths of the seed's reflected cone {wo : θh(wi, wo) = a} along the same axes.

    Pure geometry: the horizon is ignored (wo may be below it); peak = 0.
    """
    theta = np.atleast_1d(np.asarray(theta_i, dtype=np.float64))
    wi, m, up, perp = _axes(theta)

    def inside(e: FloatArray) -> Callable[[FloatArray], FloatArray]:
        def a_minus_theta_h(s: FloatArray) -> FloatArray:
            h = wi + _along(m, e, s[:, None])[:, 0, :]
            theta_h = np.arctan2(np.hypot(h[:, 0], h[:, 1]), h[:, 2])
            return np.asarray(cone_half_angle - theta_h, dtype=np.float64)

        return a_minus_theta_h

    lo, hi = np.zeros_like(theta), np.full_like(theta, np.pi / 2)
    axes = {"up": up, "down": -up, "perp": perp}
    w = {key: _bisect(inside(e), lo, hi) for key, e in axes.items()}
    no = np.zeros(theta.shape, dtype=bool)
    return LobeWidths(theta, w["up"], w["down"], w["perp"], np.zeros_like(theta), no)


def seed_closed_form_aspect(theta_i: ArrayLike, cone_half_angle: float) -> FloatArray:
    """2a / δ with sin(δ/2) = sin a cos θ: the L_min / L_max semi-axes
    of the lobe-anisotropy derivation."""
    theta = np.asarray(theta_i, dtype=np.float64)
    a = cone_half_angle
    return np.asarray(a / np.arcsin(np.sin(a) * np.cos(theta)), dtype=np.float64)


#: The study's cases: (distribution, α) and incidence angles in degrees.
CASES = (("ggx", 0.1), ("ggx", 0.3), ("beckmann", 0.1), ("beckmann", 0.3))
ANGLES_DEG = (0.0, 20.0, 40.0, 60.0, 70.0, 80.0)


def study_model(distribution: str, alpha: float, fresnel: str = "schlick") -> BRDF:
    """The study's model: cook_torrance, Schlick Fresnel with f0 = 0.04 (or F = 1: "none")."""
    return create("cook_torrance", alpha=alpha, distribution=distribution, fresnel=fresnel)


def _fmt(x: float) -> str:
    return "—" if not np.isfinite(x) else f"{x:.4f}"


def aspect_table() -> str:
    """The lobe-anisotropy table of docs/explanations/brdf.md, as markdown."""
    theta = np.radians(ANGLES_DEG)
    lines = [
        "| D | α | θi | f·cosθo, Schlick | f·cosθo, F = 1 | f, Schlick | seed cone "
        "| seed closed form | peak f·cosθo, Schlick / F = 1 | notes |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for dist, alpha in CASES:
        a = half_max_angle(dist, alpha)
        fc = lobe_widths(study_model(dist, alpha), theta, weight="f_cos")
        f1 = lobe_widths(study_model(dist, alpha, "none"), theta, weight="f_cos")
        ff = lobe_widths(study_model(dist, alpha), theta, weight="f")
        sc = seed_cone_widths(theta, a)
        closed = seed_closed_form_aspect(theta, a)
        for j, deg in enumerate(ANGLES_DEG):
            notes = []
            if sc.down[j] > np.pi / 2 - theta[j]:
                notes.append("seed cone crosses the horizon")
            if ff.peak_at_horizon[j]:
                notes.append("f peaks at the horizon")
            elif not np.isfinite(ff.aspect[j]):
                notes.append("f stays above half its peak down to the horizon")
            lines.append(
                f"| {dist} | {alpha:g} | {deg:g}° | {_fmt(fc.aspect[j])} | {_fmt(f1.aspect[j])} "
                f"| {_fmt(ff.aspect[j])} | {_fmt(sc.aspect[j])} | {_fmt(closed[j])} "
                f"| {np.degrees(fc.peak[j]):+.2f}° / {np.degrees(f1.peak[j]):+.2f}° "
                f"| {'; '.join(notes)} |"
            )
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - documentation generator
    print(aspect_table())
