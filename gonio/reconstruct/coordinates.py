"""The space a reconstruction interpolates in: a parametrization's coordinates (the
isotropic reduction for isotropic runs), scaled to the unit box, and the symmetries
that glue its faces together.

Scaling: each coordinate is divided by its extent (the parametrization's bounds,
`Parametrization.bounds` or ``iso_bounds``; every lower bound is 0), so every axis
spans [0, 1] — radii ‖h̄‖, ‖k‖ stay as they are, polar angles are divided by π/2,
azimuths by their period. Distances ("no sample within d") are Euclidean in this box.

Seams (docs/explanations/reconstruction.md#symmetries):

- an azimuth is periodic (2π, or π for a reciprocity-folded one): samples within
  ``margin`` of 0 are copied one period up, samples within ``margin`` of the period one
  period down;
- a radius or polar angle at 0 is a pole: (−r, φ + π) is the pair (r, φ), so samples
  within ``margin`` of 0 are mirrored to −r with their azimuths shifted as the pole
  requires (for the folded reductions the shift is a whole period: none);
- the spherical isotropic reduction keeps the pair's order, so the reciprocity fold is
  a copy of every sample as its reciprocal pair (θo, θi, −Δφ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gonio import params
from gonio.types import ArrayLike, FloatArray

_PI = math.pi

#: Per parametrization, (periodic azimuths, poles) in the isotropic and the full
#: coordinates. A periodic entry is (axis, period in radians); a pole is (radial axis,
#: ((azimuth axis, shift in radians), ...)).
Periodic = tuple[tuple[int, float], ...]
Poles = tuple[tuple[int, tuple[tuple[int, float], ...]], ...]

_ISO_SEAMS: dict[str, tuple[Periodic, Poles]] = {
    "spherical": (((2, 2 * _PI),), ((0, ((2, _PI),)), (1, ((2, _PI),)))),
    "rusinkiewicz": (((2, _PI),), ((0, ()), (1, ()))),
    "orthographic": (((2, _PI),), ((0, ()), (1, ()))),
    "hybrid": (((2, _PI),), ((0, ()), (1, ()))),
}
_FULL_SEAMS: dict[str, tuple[Periodic, Poles]] = {
    "spherical": (((1, 2 * _PI), (3, 2 * _PI)), ((0, ((1, _PI),)), (2, ((3, _PI),)))),
    "rusinkiewicz": (((1, 2 * _PI), (3, 2 * _PI)), ((0, ((1, _PI), (3, _PI))), (2, ((3, _PI),)))),
    "orthographic": (((1, 2 * _PI), (3, 2 * _PI)), ((0, ((1, _PI),)), (2, ((3, _PI),)))),
    "hybrid": (((1, 2 * _PI), (3, 2 * _PI)), ((0, ((1, _PI),)), (2, ((3, _PI),)))),
}

#: A copy closer than this (scaled units) to the sample it copies is the sample itself
#: (a sample on the spherical diagonal θi = θo, Δφ ∈ {0, π} is its own reciprocal).
SAME_POINT = 1e-9
#: The displacement (scaled units) given to seam copies (see `Space.pad`).
JITTER = 1e-6


@dataclass(frozen=True)
class Padded:
    """Samples with their seam copies: scaled points (M, d) and, for each, the index of
    the measured sample it copies (the first N rows are the samples themselves)."""

    points: FloatArray
    source: np.ndarray


@dataclass(frozen=True)
class Space:
    """The scaled coordinate space of one parametrization, isotropic or not."""

    parametrization: str
    isotropic: bool
    extent: FloatArray = field(init=False)
    periods: Periodic = field(init=False)
    poles: Poles = field(init=False)

    def __post_init__(self) -> None:
        p = params.get(self.parametrization)  # UnknownNameError (one line) for a bad name
        bounds = np.asarray(p.iso_bounds if self.isotropic else p.bounds, dtype=np.float64)
        extent = bounds[:, 1] - bounds[:, 0]
        table = _ISO_SEAMS if self.isotropic else _FULL_SEAMS
        periodic, poles = table[self.parametrization]
        # Every seam is expressed in scaled units (an azimuth's period is its extent: 1).
        object.__setattr__(self, "extent", extent)
        object.__setattr__(self, "periods", tuple((a, P / extent[a]) for a, P in periodic))
        object.__setattr__(
            self,
            "poles",
            tuple((r, tuple((a, s / extent[a]) for a, s in shifts)) for r, shifts in poles),
        )

    @property
    def dims(self) -> int:
        return len(self.extent)

    @property
    def names(self) -> tuple[str, ...]:
        p = params.get(self.parametrization)
        return tuple(p.iso_names if self.isotropic else p.names)

    @property
    def reciprocal_copies(self) -> bool:
        """The spherical isotropic reduction keeps the pair's order (see module doc)."""
        return self.isotropic and self.parametrization == "spherical"

    def scaled(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """Scaled coordinates (..., d) of direction pairs (..., 3) in the upper hemisphere."""
        p = params.get(self.parametrization)
        raw = p.forward_iso(wi, wo) if self.isotropic else p.forward(wi, wo)
        return np.asarray(raw / self.extent, dtype=np.float64)

    def reciprocal(self, x: FloatArray) -> FloatArray:
        """Spherical isotropic (θi, θo, Δφ) → (θo, θi, −Δφ mod 2π), scaled units."""
        swapped = x[:, [1, 0, 2]].copy()
        swapped[:, 2] = np.mod(-swapped[:, 2], 1.0)
        return swapped

    def pad(self, x: FloatArray, margin: float) -> Padded:
        """The samples ``x`` (N, d), scaled, with their copies across every seam that lie
        within ``margin`` (scaled units) of it; see the module docstring."""
        points = np.asarray(x, dtype=np.float64)
        source = np.arange(len(points))
        if self.reciprocal_copies:
            copy = self.reciprocal(points)
            distinct = np.linalg.norm(copy - points, axis=1) > SAME_POINT
            points = np.concatenate([points, copy[distinct]])
            source = np.concatenate([source, source[distinct]])
        for radial, shifts in self.poles:
            near = points[:, radial] < margin
            copy = points[near].copy()
            copy[:, radial] *= -1.0
            for axis, shift in shifts:
                copy[:, axis] = np.mod(copy[:, axis] + shift, 1.0)
            points = np.concatenate([points, copy])
            source = np.concatenate([source, source[near]])
        for axis, period in self.periods:
            low = points[:, axis] < margin
            high = points[:, axis] > period - margin
            up, down = points[low].copy(), points[high].copy()
            up[:, axis] += period
            down[:, axis] -= period
            points = np.concatenate([points, up, down])
            source = np.concatenate([source, source[low], source[high]])
        # Exact mirror copies make cocircular quadruples with their originals (flat
        # Delaunay simplices, which stall point location); a displacement far below
        # any measurement's precision makes them generic.
        n = len(x)
        points[n:] += JITTER * np.random.default_rng(0).standard_normal(points[n:].shape)
        return Padded(points, source)

    def canonical(self, x: FloatArray) -> FloatArray:
        """Points (M, d) of the padded space brought back to the measured box: a negative
        radius mirrored through its pole, azimuths wrapped into [0, period)."""
        out = np.array(x, dtype=np.float64)
        for radial, shifts in self.poles:
            mirrored = out[:, radial] < 0.0
            out[:, radial] = np.abs(out[:, radial])
            for axis, shift in shifts:
                out[:, axis] = np.where(mirrored, out[:, axis] + shift, out[:, axis])
        for axis, period in self.periods:
            out[:, axis] = np.mod(out[:, axis], period)
        return out


def morton_order(x: FloatArray) -> np.ndarray:
    """A permutation visiting the points (N, d) along a Z-order curve, so that points
    near in space are near in order (point location walks from one query's simplex to
    the next; sample tables read close together)."""
    d = x.shape[1]
    bits = 60 // d
    lo, hi = x.min(axis=0), x.max(axis=0)
    cells = ((x - lo) / np.where(hi > lo, hi - lo, 1.0) * ((1 << bits) - 1)).astype(np.uint64)
    code = np.zeros(len(x), dtype=np.uint64)
    for bit in range(bits):
        for axis in range(d):
            b = (cells[:, axis] >> np.uint64(bit)) & np.uint64(1)
            code |= b << np.uint64(bit * d + axis)
    return np.argsort(code, kind="stable")
