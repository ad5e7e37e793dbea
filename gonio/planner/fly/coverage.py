"""Fly plans' coverage figures: how the readings cover the reach.

Coverage: the total-variation distance (half the L1 distance) between the readings'
histogram in the plan's coordinates (`COVERAGE_BINS` bins a coordinate over its box)
and that of `COVERAGE_POINTS` Sobol points kept where the rig reaches them (the uniform
target density); beside it, the same figure for a uniform stop-and-go plan of as many
targets (a second Sobol sequence), the noise floor of a uniform plan of that size. A
second figure: the largest empty ball (the largest distance, unit box, from a reference
point to its nearest reading), the same for the uniform plan.

The reference points are kept per rig (the rig object: its kinematics and alignment do
not change) for each parametrization, isotropy and seed: every build of a fly plan
needs them, and fitting a plan to a time budget builds it several times over.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from gonio.planner import placement, sampling
from gonio.planner.fly.lines import box
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig
from gonio.types import FloatArray

#: Sobol points (kept where the rig reaches them) standing for the uniform density.
COVERAGE_POINTS = 1 << 15
#: Bins a coordinate for the coverage figure, by the number of coordinates.
COVERAGE_BINS = {3: 8, 4: 5}


#: Reference points of each rig, by (parametrization, isotropic, seed) (read-only).
_REFERENCES: weakref.WeakKeyDictionary[Rig, dict[tuple[str, bool, int], FloatArray]] = (
    weakref.WeakKeyDictionary()
)


def reference(spec: PlanSpec, rig: Rig) -> FloatArray:
    """`COVERAGE_POINTS` Sobol points kept where the rig reaches them (the uniform
    target density), scaled to the unit box (read-only: kept for the next call)."""
    known = _REFERENCES.setdefault(rig, {})
    key = (spec.parametrization, spec.isotropic, spec.sampling.seed)
    if key not in known:
        points = _reference(spec, rig)
        points.setflags(write=False)
        known[key] = points
    return known[key]


def _reference(spec: PlanSpec, rig: Rig) -> FloatArray:
    bounds = box(spec)
    d = len(bounds)
    stream = sampling.Sequence("sobol", d, spec.sampling.seed + 7919)
    points = sampling.to_box(stream.draw(COVERAGE_POINTS), bounds, np.ones(d))
    points = points[placement.kept_mask(spec, rig, points)]
    return np.asarray((points - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0]))


@dataclass(frozen=True)
class Coverage:
    """How the readings cover the reach (`coverage`)."""

    tv: float  # total-variation distance to the uniform density over the reach
    tv_uniform: float  # the same of a uniform Sobol plan of as many targets
    bins: int  # bins a coordinate
    gap: float  # the largest empty ball's radius (unit box) centred in the reach
    gap_uniform: float  # the same of the uniform plan


def coverage(
    spec: PlanSpec, rig: Rig, where: str, coords: FloatArray, ref: FloatArray | None = None
) -> Coverage:
    """How ``coords`` (N, D) cover the uniform density over what the rig reaches, and
    how a uniform Sobol plan of as many targets does (the module docstring)."""
    bounds = box(spec)
    d = len(bounds)
    bins = COVERAGE_BINS.get(d, 5)
    ones = np.ones(d)
    target_points = reference(spec, rig) if ref is None else ref
    uniform_stream = sampling.Sequence("sobol", d, spec.sampling.seed + 1)
    uniform = placement.draw_kept(
        spec, rig, where, lambda k: sampling.to_box(uniform_stream.draw(k), bounds, ones),
        min(len(coords), COVERAGE_POINTS),
    )  # fmt: skip
    uniform = uniform[placement.kept_mask(spec, rig, uniform)]

    def unit(x: FloatArray) -> FloatArray:
        return np.asarray((x - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0]))

    def histogram(u: FloatArray) -> FloatArray:
        cell = np.clip(np.floor(u * bins).astype(np.int64), 0, bins - 1)
        flat = np.ravel_multi_index(tuple(cell.T), (bins,) * d)
        counts = np.bincount(flat, minlength=bins**d).astype(np.float64)
        return np.asarray(counts / max(counts.sum(), 1.0), dtype=np.float64)

    def gap(u: FloatArray) -> float:
        return float(cKDTree(u).query(target_points)[0].max())

    target = histogram(target_points)
    got, even = unit(coords), unit(uniform)
    return Coverage(
        tv=0.5 * float(np.abs(histogram(got) - target).sum()),
        tv_uniform=0.5 * float(np.abs(histogram(even) - target).sum()),
        bins=bins, gap=gap(got), gap_uniform=gap(even),
    )  # fmt: skip
