"""Named extreme configurations and samplers of pairs near them.

Used by the tests, the accuracy study (studies/extremes.py, docs) and `gonio tables`.
Every sampler returns float64 unit directions (unit to float64 rounding) in the
closed upper hemisphere, shape (n, 3) each; ``distance`` is how far, in radians, the
pair is moved off the extreme (0 gives the extreme itself with random generic
remaining parameters).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gonio.types import FloatArray

Pair = tuple[FloatArray, FloatArray]
Sampler = Callable[[np.random.Generator, int, float], Pair]


def direction(theta: FloatArray | float, phi: FloatArray | float) -> FloatArray:
    """Unit vectors (..., 3) at polar angle θ and azimuth φ."""
    t, p = np.broadcast_arrays(np.asarray(theta, np.float64), np.asarray(phi, np.float64))
    s = np.sin(t)
    return np.asarray(np.stack([s * np.cos(p), s * np.sin(p), np.cos(t)], axis=-1), np.float64)


def elevated(elevation: FloatArray | float, phi: FloatArray | float) -> FloatArray:
    """Unit vectors at ``elevation`` above the horizon (exactly z = 0 at elevation 0)."""
    e, p = np.broadcast_arrays(np.asarray(elevation, np.float64), np.asarray(phi, np.float64))
    c = np.cos(e)
    return np.asarray(np.stack([c * np.cos(p), c * np.sin(p), np.sin(e)], axis=-1), np.float64)


def mirror(w: FloatArray) -> FloatArray:
    """The mirror direction about the normal: (−x, −y, z)."""
    return np.asarray(w * np.array([-1.0, -1.0, 1.0]), dtype=np.float64)


def tilt(w: FloatArray, angle: FloatArray | float, rng: np.random.Generator) -> FloatArray:
    """``w`` rotated by ``angle`` toward a random perpendicular, kept in z ≥ 0."""
    a = np.asarray(angle, np.float64)[..., None]
    r = rng.normal(size=w.shape)
    r -= np.sum(r * w, axis=-1, keepdims=True) * w
    r /= np.linalg.norm(r, axis=-1, keepdims=True)
    out = np.cos(a) * w + np.sin(a) * r
    out[..., 2] = np.abs(out[..., 2])
    return np.asarray(out / np.linalg.norm(out, axis=-1, keepdims=True), dtype=np.float64)


def generic(rng: np.random.Generator, n: int) -> FloatArray:
    """Directions away from every extreme: θ in [15°, 70°], any azimuth."""
    return direction(rng.uniform(np.radians(15), np.radians(70), n), rng.uniform(0, 2 * np.pi, n))


def _phi(rng: np.random.Generator, n: int) -> FloatArray:
    return rng.uniform(0.0, 2.0 * np.pi, n)


def _normal_incidence_i(rng: np.random.Generator, n: int, d: float) -> Pair:
    return direction(np.full(n, d), _phi(rng, n)), generic(rng, n)


def _normal_incidence_o(rng: np.random.Generator, n: int, d: float) -> Pair:
    return generic(rng, n), direction(np.full(n, d), _phi(rng, n))


def _normal_both(rng: np.random.Generator, n: int, d: float) -> Pair:
    return direction(np.full(n, d), _phi(rng, n)), direction(d * rng.random(n), _phi(rng, n))


def _grazing_i(rng: np.random.Generator, n: int, d: float) -> Pair:
    return elevated(np.full(n, d), _phi(rng, n)), generic(rng, n)


def _grazing_o(rng: np.random.Generator, n: int, d: float) -> Pair:
    return generic(rng, n), elevated(np.full(n, d), _phi(rng, n))


def _grazing_both(rng: np.random.Generator, n: int, d: float) -> Pair:
    return elevated(np.full(n, d), _phi(rng, n)), elevated(d * rng.random(n), _phi(rng, n))


def _retro(rng: np.random.Generator, n: int, d: float) -> Pair:
    wi = generic(rng, n)
    return wi, tilt(wi, np.full(n, d), rng)


def _retro_grazing(rng: np.random.Generator, n: int, d: float) -> Pair:
    wi = elevated(d * rng.random(n), _phi(rng, n))
    return wi, tilt(wi, np.full(n, d), rng)


def _mirror(rng: np.random.Generator, n: int, d: float) -> Pair:
    wi = generic(rng, n)
    return wi, tilt(mirror(wi), np.full(n, d), rng)


def _opposite_grazing(rng: np.random.Generator, n: int, d: float) -> Pair:
    phi = _phi(rng, n)
    wi = elevated(d * rng.random(n), phi)
    wo = elevated(d * rng.random(n), phi + np.pi + d * rng.uniform(-1.0, 1.0, n))
    return wi, wo


#: name → (description, sampler). The descriptions name the coordinate that is extreme.
EXTREMES: dict[str, tuple[str, Sampler]] = {
    "normal_incidence_i": ("ωi = n (θi = 0)", _normal_incidence_i),
    "normal_incidence_o": ("ωo = n (θo = 0)", _normal_incidence_o),
    "normal_both": ("ωi = ωo = n (‖h̄‖ = ‖k‖ = 0)", _normal_both),
    "grazing_i": ("θi = 90°", _grazing_i),
    "grazing_o": ("θo = 90°", _grazing_o),
    "grazing_both": ("θi = θo = 90°, any azimuths", _grazing_both),
    "retro": ("retro-reflection ωi = ωo (‖k‖ = 0)", _retro),
    "retro_grazing": ("retro-reflection on the horizon", _retro_grazing),
    "mirror": ("mirror configuration (‖h̄‖ = 0)", _mirror),
    "opposite_grazing": ("opposite grazing ωi = −ωo (‖k‖ = 1)", _opposite_grazing),
}

#: Distances (radians) at which the accuracy study samples each extreme.
DISTANCES = (0.0, 1e-12, 1e-9, 1e-6)


def near(name: str, distance: float, n: int, seed: int = 0) -> Pair:
    """``n`` pairs at ``distance`` from the extreme ``name`` (see `EXTREMES`)."""
    return EXTREMES[name][1](np.random.default_rng(seed), n, distance)


def uniform(n: int, seed: int = 0) -> Pair:
    """``n`` pairs of directions drawn uniformly (by solid angle) on the hemisphere."""
    rng = np.random.default_rng(seed)

    def hemisphere() -> FloatArray:
        v = rng.normal(size=(n, 3))
        v[:, 2] = np.abs(v[:, 2])
        return np.asarray(v / np.linalg.norm(v, axis=1, keepdims=True), dtype=np.float64)

    return hemisphere(), hemisphere()


def away(n: int, seed: int = 0) -> Pair:
    """``n`` generic pairs, away from every extreme."""
    rng = np.random.default_rng(seed)
    return generic(rng, n), generic(rng, n)


def near_horizon(n: int, seed: int = 0) -> Pair:
    """``n`` pairs crossing the √ε regime: ωi at an elevation log-uniform in 1e-10 … 1e-5;
    ωo (by quarters, at random) also near the horizon at any azimuth, near
    retro-reflection, near the opposite direction, or generic."""
    rng = np.random.default_rng(seed)
    e1, e2 = 10 ** rng.uniform(-10, -5, n), 10 ** rng.uniform(-10, -5, n)
    phi = _phi(rng, n)
    twist = 10 ** rng.uniform(-8, -2, n) * rng.choice([-1.0, 1.0], n)
    partners = np.stack(
        [
            elevated(e2, _phi(rng, n)),
            elevated(e2, phi + twist),
            elevated(e2, phi + np.pi + twist),
            generic(rng, n),
        ]
    )
    wo = partners[rng.integers(0, 4, n), np.arange(n)]
    return elevated(e1, phi), np.asarray(wo, dtype=np.float64)


#: Named single pairs for the demo table: (ωi, ωo).
NAMED_PAIRS: dict[str, Pair] = {
    "generic": (direction(np.radians(30), 0.3), direction(np.radians(50), 2.5)),
    "normal incidence": (direction(0.0, 0.0), direction(np.radians(40), 1.0)),
    "θi = 90°": (elevated(0.0, 0.7), direction(np.radians(35), 4.0)),
    "both θ = 90°": (elevated(0.0, 0.2), elevated(0.0, 2.0)),
    "retro-reflection": (direction(np.radians(40), 1.0), direction(np.radians(40), 1.0)),
    "mirror": (direction(np.radians(40), 1.0), mirror(direction(np.radians(40), 1.0))),
    "opposite grazing": (elevated(0.0, 1.0), elevated(0.0, 1.0 + np.pi)),
    "ωi = ωo = n": (direction(0.0, 0.0), direction(0.0, 0.0)),
    "grazing, 1e-9 off": (elevated(1e-9, 0.5), elevated(2e-9, 2.0)),
}


def roundtrip_error(wi: FloatArray, wo: FloatArray, wi2: FloatArray, wo2: FloatArray) -> FloatArray:
    """max(‖ωi' − ωi‖, ‖ωo' − ωo‖) per pair (Euclidean, ≈ the angle in radians)."""
    return np.asarray(
        np.maximum(np.linalg.norm(wi2 - wi, axis=-1), np.linalg.norm(wo2 - wo, axis=-1)),
        dtype=np.float64,
    )
