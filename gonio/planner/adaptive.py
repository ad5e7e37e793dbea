"""Adaptive placement: the remaining budget of a plan placed with a density that follows
where a piecewise-linear reconstruction errs, estimated from a survey.

The reconstruction interpolates g = log(f + ε) linearly in the parametrization's scaled
coordinates (the unit box; docs/explanations/reconstruction.md), ε = `LOG_FLOOR`, and is
scored on log(1 + f) over pairs uniform in dωi dωo (the test set,
docs/explanations/evaluation.md). Locally the interpolation error of g is about h²‖∇²g‖
for a spacing h, and it reaches the metric through d log(1 + f)/dg = f/(1 + f). With w
the density of the test measure in the unit box and ρ the sample density
(h ∝ ρ^(−1/d)), the expected squared error ∫ w (f/(1 + f))² ‖∇²g‖² ρ^(−4/d) is least for

    ρ ∝ (w · (f/(1 + f))² · ‖∇²g‖²)^(d/(d + 4))

(the classic optimal-mesh density for linear interpolation). ``f`` here is an estimate:
a model fitted to the survey (from a family the caller chooses) or any callable. The
density is piecewise constant on a grid of cells, mixed with a uniform ``floor`` over
the cells the rig reaches so that every region keeps some samples, and sampled by
inverse CDF driven by a scrambled Sobol sequence (seeded, deterministic). Whether a
plan follows the density at all is decided from its survey (`gonio.planner.choice`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.stats import qmc

from gonio import params
from gonio.brdf import LOG_FLOOR
from gonio.directions import uniform_cap
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray

#: Cells per axis of the density grid, by dimension (3: isotropic, 4: anisotropic).
CELLS = {3: 32, 4: 14}
#: Pairs drawn uniformly in dωi dωo to estimate the test measure's density per cell.
MEASURE_PAIRS = 1 << 18
#: Seed of those pairs (a fixed number: the density does not depend on the plan's seed).
MEASURE_SEED = 20261
#: Default share of the remaining budget placed uniformly over the reachable cells.
FLOOR = 0.25


@dataclass(frozen=True)
class Density:
    """A piecewise-constant probability density on the unit box: ``p`` (cells,) in C
    order over a grid of ``shape``, summing to 1."""

    shape: tuple[int, ...]
    p: FloatArray

    def points(self, unit: FloatArray) -> FloatArray:
        """Points (N, d) of the unit box distributed by the density, from unit-cube points
        (N, d + 1): the first coordinate picks the cell by inverse CDF, the others place
        the point inside it."""
        cdf = np.cumsum(self.p)
        cell = np.searchsorted(cdf, unit[:, 0] * cdf[-1], side="right")
        cell = np.minimum(cell, len(self.p) - 1)
        index = np.stack(np.unravel_index(cell, self.shape), axis=-1).astype(np.float64)
        return np.asarray((index + unit[:, 1:]) / np.asarray(self.shape), dtype=np.float64)


class Stream:
    """An endless stream of points distributed by a `Density` (scrambled Sobol)."""

    def __init__(self, density: Density, seed: int) -> None:
        self.density = density
        self._engine = qmc.Sobol(len(density.shape) + 1, scramble=True, seed=seed)

    def draw(self, n: int) -> FloatArray:
        return self.density.points(np.asarray(self._engine.random(n), dtype=np.float64))


def cell_index(unit: FloatArray, shape: tuple[int, ...]) -> np.ndarray:
    """The flat (C order) index of the cell of a ``shape`` grid on the unit box holding
    each point (N, d); points on or beyond the box's faces go to the nearest cell."""
    dims = np.asarray(shape)
    index = np.clip(np.floor(unit * dims).astype(np.int64), 0, dims - 1)
    return np.asarray(np.ravel_multi_index(tuple(index.T), shape))


def centres(shape: tuple[int, ...]) -> FloatArray:
    """The cell centres (cells, d) of a grid on the unit box, C order."""
    axes = [(np.arange(n, dtype=np.float64) + 0.5) / n for n in shape]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(shape))


def _bounds(parametrization: str, isotropic: bool) -> FloatArray:
    p = params.get(parametrization)
    return np.asarray(p.iso_bounds if isotropic else p.bounds, dtype=np.float64)


_MEASURES: dict[tuple[bytes, str, bool, tuple[int, ...], int], FloatArray] = {}


def measure_density(
    rig: Rig, parametrization: str, isotropic: bool, shape: tuple[int, ...]
) -> FloatArray:
    """The test measure's share of each cell (cells,), summing to 1: pairs uniform in
    dωi dωo over the rig's cap and reach, mapped to the unit box and counted per cell,
    smoothed over one cell (the count is an estimate). Kept per rig text (seconds)."""
    key = (rig.text, parametrization, isotropic, shape, MEASURE_PAIRS)
    if key not in _MEASURES:
        _MEASURES[key] = _measure_density(rig, parametrization, isotropic, shape)
        _MEASURES[key].setflags(write=False)
    return _MEASURES[key]


def _measure_density(
    rig: Rig, parametrization: str, isotropic: bool, shape: tuple[int, ...]
) -> FloatArray:
    rng = np.random.default_rng(MEASURE_SEED)
    wi = uniform_cap(rng, MEASURE_PAIRS, rig.theta_max)
    wo = uniform_cap(rng, MEASURE_PAIRS, rig.theta_max)
    ok, _ = rig.reachable(wi, wo, isotropic=isotropic)
    p = params.get(parametrization)
    coords = p.forward_iso(wi[ok], wo[ok]) if isotropic else p.forward(wi[ok], wo[ok])
    bounds = _bounds(parametrization, isotropic)
    unit = (coords - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    counts = np.bincount(cell_index(unit, shape), minlength=math.prod(shape)).astype(np.float64)
    smooth = ndimage.gaussian_filter(counts.reshape(shape), 1.0, mode="nearest").ravel()
    smooth = np.where(counts > 0, smooth, 0.0)  # cells nobody reaches stay empty
    return np.asarray(smooth / smooth.sum(), dtype=np.float64)


def error_indicator(
    f: BrdfEval,
    parametrization: str,
    isotropic: bool,
    shape: tuple[int, ...],
    dims: tuple[int, ...] | None = None,
) -> FloatArray:
    """(f/(1 + f))·‖∇²log(f + ε)‖_F at each cell centre (cells,), derivatives in the
    unit box by central differences on the grid (outside the parametrization's domain
    the nearest valid cell's value is used); ``dims``: only the second derivatives in
    these coordinates (default all)."""
    p = params.get(parametrization)
    bounds = _bounds(parametrization, isotropic)
    box = bounds[:, 0] + centres(shape) * (bounds[:, 1] - bounds[:, 0])
    valid = p.valid_iso(box) if isotropic else p.valid(box)
    values = np.zeros(len(box))
    wi, wo = p.inverse_iso(box[valid]) if isotropic else p.inverse(box[valid])
    f_valid = np.asarray(f(wi, wo), dtype=np.float64)
    if f_valid.ndim == 2:
        f_valid = f_valid.mean(axis=1)
    values[valid] = np.maximum(f_valid, 0.0)
    grid = values.reshape(shape)
    if not valid.all():
        _, nearest = ndimage.distance_transform_edt(
            ~valid.reshape(shape), return_distances=True, return_indices=True
        )
        grid = grid[tuple(nearest)]
    g = np.log(grid + LOG_FLOOR)
    steps = [1.0 / n for n in shape]
    first = np.gradient(g, *steps)
    square = np.zeros_like(g)
    keep = range(len(shape)) if dims is None else dims
    for i, d_i in enumerate(first):
        for j, d_ij in enumerate(np.gradient(d_i, *steps)):
            if i in keep and j in keep:
                square += d_ij**2
    return np.asarray((np.sqrt(square) * grid / (1.0 + grid)).ravel(), dtype=np.float64)


@dataclass(frozen=True)
class ErrorMap:
    """What the density is made of, per cell of a grid of ``shape`` (C order): the test
    measure's share ``w`` and the error indicator ``e`` of the estimate (`error_indicator`)."""

    shape: tuple[int, ...]
    w: FloatArray
    e: FloatArray

    @property
    def uniform(self) -> FloatArray:
        """The uniform density over the cells the test measure reaches (cells,)."""
        reached = (self.w > 0).astype(np.float64)
        return np.asarray(reached / reached.sum(), dtype=np.float64)

    def density(self, floor: float) -> Density:
        """The optimal density of the module docstring, a share ``floor`` of it uniform."""
        dims = len(self.shape)
        optimal = np.power(self.w * self.e**2, dims / (dims + 4.0))
        total = optimal.sum()
        shaped = optimal / total if total > 0 else self.uniform
        p = (1.0 - floor) * shaped + floor * self.uniform
        return Density(self.shape, np.asarray(p, dtype=np.float64))


def error_map(f: BrdfEval, rig: Rig, parametrization: str, isotropic: bool) -> ErrorMap:
    """The test measure and the error indicator of the estimate ``f`` on the density grid
    (`CELLS`)."""
    dims = 3 if isotropic else 4
    shape = (CELLS[dims],) * dims
    w = measure_density(rig, parametrization, isotropic, shape)
    return ErrorMap(shape, w, error_indicator(f, parametrization, isotropic, shape))


def density(
    f: BrdfEval,
    rig: Rig,
    parametrization: str,
    isotropic: bool,
    *,
    floor: float = FLOOR,
) -> Density:
    """The sample density of the module docstring for the estimate ``f``, a share
    ``floor`` of it uniform over the cells the test measure reaches."""
    return error_map(f, rig, parametrization, isotropic).density(floor)


#: How far inside the rig's cap (radians) a point moved onto its edge is put.
EDGE_MARGIN = 1e-6


def onto_edge(
    coords: FloatArray, rig: Rig, parametrization: str, isotropic: bool
) -> tuple[FloatArray, np.ndarray]:
    """Points (N, d) moved onto the edge of the rig's cap: the direction of each pair
    with the larger polar angle (and the other one too if it is beyond the edge) turned
    to θmax − `EDGE_MARGIN`, its azimuth kept; and
    a mask (N,) of the points moved (those in the parametrization's domain).

    A piecewise-linear reconstruction answers only inside the hull of its samples, and
    the test measure reaches θmax: without samples on the edge the pairs near it are
    extrapolated, which is where most of the error of a glossy material sits (the
    grazing specular peak; docs/explanations/adaptive.md). Moving points drawn from the density
    puts the edge's samples where the density is high next to it."""
    p = params.get(parametrization)
    valid = p.valid_iso(coords) if isotropic else p.valid(coords)
    out = np.array(coords, dtype=np.float64)
    wi, wo = p.inverse_iso(coords[valid]) if isotropic else p.inverse(coords[valid])
    edge = math.cos(rig.theta_max - EDGE_MARGIN)
    # The lower direction goes onto the edge, the other too if it is beyond it.
    incident = (wi[:, 2] <= wo[:, 2]) | (wi[:, 2] < edge)
    outgoing = (wo[:, 2] < wi[:, 2]) | (wo[:, 2] < edge)
    wi = np.where(incident[:, None], _with_cos(wi, edge), wi)
    wo = np.where(outgoing[:, None], _with_cos(wo, edge), wo)
    out[valid] = p.forward_iso(wi, wo) if isotropic else p.forward(wi, wo)
    return out, np.asarray(valid, dtype=np.bool_)


def _with_cos(w: FloatArray, z: float) -> FloatArray:
    """Directions (N, 3) turned to polar cosine ``z``, their azimuths kept (the normal
    itself goes to azimuth 0)."""
    rho = np.hypot(w[:, 0], w[:, 1])
    s = math.sqrt(max(1.0 - z * z, 0.0))
    safe = np.where(rho > 0, rho, 1.0)
    x = np.where(rho > 0, w[:, 0] / safe, 1.0)
    y = np.where(rho > 0, w[:, 1] / safe, 0.0)
    return np.stack([s * x, s * y, np.full(len(w), z)], axis=-1)
