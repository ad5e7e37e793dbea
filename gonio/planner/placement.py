"""Placing a plan's points: uniform (or warped) in the parametrization's coordinate box
or its isotropic reduction, by grid, stratified, Sobol, Halton or random sampling; a
sequence is drawn in batches until enough points are kept (valid coordinates the rig
can reach)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from gonio import params, progress
from gonio.config import ConfigError
from gonio.planner import sampling
from gonio.planner.schema import MAX_TARGETS as MAX_TARGETS  # builder reads the cap here
from gonio.planner.schema import WHY_MAX_TARGETS, PlanSpec
from gonio.rig import Rig
from gonio.types import FloatArray

#: Sequence strategies draw in batches of this many points (a power of two for Sobol).
BATCH = 4096
#: A plan asking for a target count stops drawing after this many points; a grid has at
#: most this many cells.
MAX_DRAWN = 4_000_000


def too_many(where: str, field: str, count: int) -> ConfigError:
    """The error of a plan that would keep more than `MAX_TARGETS` targets."""
    return ConfigError(
        f"{where}: {field}: expected at most {MAX_TARGETS:,} targets, got {count:,} "
        f"({WHY_MAX_TARGETS})"
    )


def place(spec: PlanSpec, rig: Rig, where: str) -> tuple[FloatArray, tuple[int, ...] | None]:
    """The points placed in the coordinate box, in generation order, and the grid shape."""
    p = params.get(spec.parametrization)
    names = spec.coordinates()
    bounds = np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)
    powers = np.array(
        [spec.sampling.warps[n].power if n in spec.sampling.warps else 1.0 for n in names]
    )
    s = spec.sampling
    if s.target is not None and s.target > MAX_TARGETS:
        raise too_many(where, "sampling.target", s.target)
    if s.strategy in ("grid", "stratified"):
        if s.counts is not None:
            shape = tuple(s.counts[n] for n in names)
            field = "sampling.counts"
        else:
            assert s.target is not None
            pilot = sampling.to_box(
                sampling.Sequence("sobol", len(names), s.seed).draw(BATCH), bounds, powers
            )
            rate = max(kept_mask(spec, rig, pilot).mean(), 1.0 / BATCH)
            shape = sampling.grid_shape_for((s.target / rate) ** (1.0 / len(names)), len(names))
            field = "sampling.target"
        cells = math.prod(shape)
        if cells > MAX_DRAWN:
            raise ConfigError(
                f"{where}: {field}: a {'×'.join(map(str, shape))} grid is {cells:,} points; "
                f"expected at most {MAX_DRAWN:,}"
            )
        jitter = np.random.default_rng(s.seed) if s.strategy == "stratified" else None
        unit = sampling.grid(shape, jitter=jitter)
        return sampling.to_box(unit, bounds, powers), shape
    assert s.target is not None
    # The adaptive strategy's first pass is a Sobol survey (`gonio.planner.two_pass`).
    adaptive = s.strategy == "adaptive"
    target = s.options().survey if adaptive else s.target
    stream = sampling.Sequence("sobol" if adaptive else s.strategy, len(names), s.seed)
    return draw_kept(
        spec, rig, where, lambda n: sampling.to_box(stream.draw(n), bounds, powers), target
    ), None


def draw_kept(
    spec: PlanSpec, rig: Rig, where: str, draw: Callable[[int], FloatArray], target: int
) -> FloatArray:
    """Points drawn in batches from ``draw`` until ``target`` are kept (valid and
    reachable): every point drawn up to the one completing the target, in order."""
    drawn: list[FloatArray] = []
    usable: list[np.ndarray] = []
    kept = 0
    with progress.stage("placing the targets", target) as shown:
        while kept < target:
            if sum(len(d) for d in drawn) >= MAX_DRAWN:
                raise ConfigError(
                    f"{where}: sampling.target: only {kept} of {target} targets are "
                    f"reachable after {MAX_DRAWN} points; lower the target or relax the "
                    "rig's constraints"
                )
            batch = draw(BATCH)
            usable.append(kept_mask(spec, rig, batch))
            new = int(usable[-1].sum())
            shown.advance(min(new, target - kept))
            kept += new
            drawn.append(batch)
    points = np.concatenate(drawn)
    keep = np.cumsum(np.concatenate(usable))
    last = int(np.searchsorted(keep, target)) + 1  # the point that completes the target
    return points[:last]


def directions(spec: PlanSpec, coords: FloatArray) -> tuple[np.ndarray, FloatArray, FloatArray]:
    """(valid mask, ωi, ωo of the valid points)."""
    p = params.get(spec.parametrization)
    if spec.isotropic:
        valid = p.valid_iso(coords)
        wi, wo = p.inverse_iso(coords[valid])
    else:
        valid = p.valid(coords)
        wi, wo = p.inverse(coords[valid])
    return valid, wi, wo


def kept_mask(spec: PlanSpec, rig: Rig, coords: FloatArray) -> np.ndarray:
    valid, wi, wo = directions(spec, coords)
    ok = np.zeros(len(coords), dtype=np.bool_)
    ok[valid] = rig.solve(wi, wo, isotropic=spec.isotropic).ok
    return ok
