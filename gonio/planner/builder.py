"""`build`: from a plan spec and a rig to an ordered, timed list of motor targets.

Points are placed uniformly in the parametrization's coordinate box (or its isotropic
reduction, `gonio.planner.placement`), kept where the coordinates are valid and the rig
can reach the pair (`solve`), mapped to joint angles, ordered for the motors
(`order_targets`), and timed with each axis's trapezoidal profile plus settle and
exposure (`timing`): at the rates the motors run and with the bus's wire time on a
Dynamixel rig (`Rig.motion_rates`, `Rig.bus_time`), the rig file's rates alone for
simulated motors. Nothing here moves a motor.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from gonio.config import ConfigError, spec_text
from gonio.planner import fly, lkh, placement, poses, sampling
from gonio.planner.bounds import held_karp_bound
from gonio.planner.exposure import check_detector, exposures
from gonio.planner.model import Plan, Summary
from gonio.planner.ordering import (
    Method,
    Ordering,
    compile_kernels,
    default_kicks,
    default_moves,
    order_jointly,
)
from gonio.planner.placement import directions, place, too_many
from gonio.planner.poses import Relaxed
from gonio.planner.schema import PlanSpec
from gonio.rig import Reason, Rig, Solution
from gonio.types import FloatArray

#: Pairs the rig solves at a time.
SOLVE_CHUNK = 32_768


@dataclass(frozen=True)
class Solved:
    """The points placed and what the rig makes of them."""

    coords: FloatArray  # (P, d) every point placed, in generation order
    shape: tuple[int, ...] | None  # a grid's shape (None: a sequence)
    valid: np.ndarray  # (P,) bool: in the parametrization's domain
    refused: dict[str, int]  # unreachable points, by reason
    kept: np.ndarray  # (K,) int64: the reachable points, as indices into coords
    sel: np.ndarray  # (K,) the same points as indices into `solution` (the valid ones)
    solution: Solution  # the inverse kinematics of the valid points


@dataclass(frozen=True)
class Ordered:
    """The kept targets in measuring order and the poses chosen for them."""

    given: np.ndarray  # (K,) the order handed to the search, as positions in `Solved.kept`
    order: np.ndarray  # (K,) the measuring order, as positions in ``given``
    angles: FloatArray  # (K, A) the pose chosen for each target, measuring order
    travel: FloatArray  # (K,) s, the move into each target
    candidates: FloatArray  # (K, S, A) every solution of each target, ``given`` order
    usable: np.ndarray  # (K, S) bool: which of them the rig allows
    ordering: Ordering  # the search's figures
    max_moves: int
    max_kicks: int
    ordering_s: float  # wall clock


def solve(
    spec: PlanSpec, rig: Rig, where: str, coords: FloatArray, shape: tuple[int, ...] | None
) -> Solved:
    """The inverse kinematics of the points, the reachable ones kept (`ConfigError` if
    there are more than `placement.MAX_TARGETS` or none)."""
    valid, wi, wo = directions(spec, coords)
    solution = _solve(rig, wi, wo, spec.isotropic)
    reasons = np.full(len(coords), -1, dtype=np.int8)  # -1: outside the domain
    reasons[valid] = solution.reasons
    refused = {r.label: int(np.count_nonzero(reasons == r)) for r in Reason if r != Reason.OK}
    kept = np.flatnonzero(reasons == Reason.OK)
    if kept.size > placement.MAX_TARGETS:
        raise too_many(where, "sampling.counts" if spec.sampling.counts else "sampling", kept.size)
    if kept.size == 0:
        detail = ", ".join(f"{k} {v}" for k, v in refused.items() if v)
        raise ConfigError(
            f"{where}: the rig's constraints leave none of the {len(coords)} points reachable "
            f"({np.count_nonzero(~valid)} outside the domain; refused: {detail or 'none'})"
        )
    in_valid = np.cumsum(valid) - 1  # index into the valid subset
    return Solved(coords, shape, valid, refused, kept, in_valid[kept], solution)


def _solve(rig: Rig, wi: FloatArray, wo: FloatArray, isotropic: bool) -> Solution:
    """`Rig.solve` of the pairs (N, 3), `SOLVE_CHUNK` at a time (its temporaries are many
    times its result)."""
    if len(wi) <= SOLVE_CHUNK:
        return rig.solve(wi, wo, isotropic=isotropic)
    parts = [
        rig.solve(wi[lo : lo + SOLVE_CHUNK], wo[lo : lo + SOLVE_CHUNK], isotropic=isotropic)
        for lo in range(0, len(wi), SOLVE_CHUNK)
    ]
    return Solution(
        *(np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(Solution))
    )


def order_targets(
    spec: PlanSpec, rig: Rig, where: str, solved: Solved, home: FloatArray
) -> Ordered:
    """The kept targets ordered from ``home``: on the relaxed any-branch time from each
    target's solution nearest home, then solutions chosen along the order and improved
    on (`order_jointly`); then LKH if the plan asks for it. Grids start from the
    serpentine over the full grid, refused cells skipped."""
    sel, solution = solved.sel, solved.solution
    method: Method
    if solved.shape is not None:
        rank = np.empty(int(np.prod(solved.shape)), dtype=np.int64)
        rank[sampling.serpentine(solved.shape)] = np.arange(rank.size)
        given = np.argsort(rank[solved.kept], kind="stable")
        targets = solution.angles[sel][given]
        method = "given"
    else:
        given, targets = np.arange(sel.size), solution.angles[sel]
        method = "auto"
    budget = default_moves(sel.size) if spec.max_moves is None else spec.max_moves
    kicks = default_kicks(sel.size) if spec.kicks is None else spec.kicks
    compile_kernels()  # a first run's compilation is not the ordering's time
    started = time.perf_counter()
    cand, usable = solution.candidates[sel][given], solution.usable[sel][given]
    joint = order_jointly(
        rig.travel,
        cand,
        usable,
        targets,
        home,
        method=method,
        max_moves=budget,
        kicks=kicks,
        seed=spec.sampling.seed,
        time_budget_s=spec.time_budget_s,
    )
    order, angles, travel = joint.order, joint.angles, joint.travel
    if spec.ordering == "lkh":
        if not lkh.available():
            raise ConfigError(f"{where}: ordering: lkh needs elkai: pip install 'gonio[lkh]'")
        order, angles, travel = lkh.improve(rig.travel, home, cand, usable, order, angles, travel)
    ordering_s = time.perf_counter() - started
    return Ordered(
        given, order, angles, travel, cand, usable, joint.ordering, budget, kicks, ordering_s
    )


def lower_bounds(rig: Rig, solved: Solved, ordered: Ordered, home: FloatArray) -> dict[str, Any]:
    """The summary's figures to compare against (s): bounds on every order with every
    choice of solutions (the relaxed time), and generation order with the exact choice
    of solutions along it."""
    relaxed = Relaxed.of(rig.travel, ordered.candidates, ordered.usable, home)
    b = held_karp_bound(relaxed, float(ordered.travel.sum()))
    sel = solved.sel
    _, naive = poses.choose(
        solved.solution.candidates[sel], solved.solution.usable[sel], home, rig.travel_time
    )
    return {
        "naive_travel_s": float(naive.sum()),
        "lower_bound_travel_s": b.held_karp_s,
        "mst_travel_s": b.mst_s,
        "lower_bound_exact": b.exact,
    }


@dataclass(frozen=True)
class Timing:
    """Each target's times (s, measuring order) and its averages: the exposures, the
    dwell (settle + exposure × averages), the bus's part of the step (`Rig.bus_time`),
    and the arrival (the moves up to it, the dwells and bus times before it)."""

    exposure: FloatArray
    averages: np.ndarray
    dwell: FloatArray
    bus: FloatArray
    arrival: FloatArray


def timing(spec: PlanSpec, rig: Rig, wi: FloatArray, wo: FloatArray, travel: FloatArray) -> Timing:
    """The `Timing` of targets measuring the pairs ``wi``, ``wo`` after moves of
    ``travel`` s."""
    exposure, averages = exposures(spec.exposure, wi, wo, rig.source_kind)
    dwell = rig.spec.settle_s + exposure * averages
    bus = rig.bus_time(travel)
    arrival = np.cumsum(travel) + np.concatenate([[0.0], np.cumsum(dwell + bus)[:-1]])
    return Timing(exposure, averages, dwell, bus, arrival)


def summarize(
    spec: PlanSpec,
    rig: Rig,
    solved: Solved,
    ordered: Ordered,
    times: Timing,
    figures: dict[str, Any],
) -> Summary:
    """The counts and times of the plan (``figures``: `lower_bounds`, or none)."""
    result = ordered.ordering
    return Summary(
        requested=len(solved.coords),
        invalid=int(np.count_nonzero(~solved.valid)),
        refused=solved.refused,
        kept=int(solved.kept.size),
        travel_s=float(ordered.travel.sum()),
        dwell_s=float(times.dwell.sum()),
        bus_s=float(times.bus.sum()),
        timing="dynamixel" if rig.on_dynamixel else "rig",
        moves=result.moves,
        max_moves=ordered.max_moves,
        kicks=result.kicks,
        kicks_kept=result.kicks_kept,
        max_kicks=ordered.max_kicks,
        stopped=result.stopped,
        time_cap_s=spec.time_budget_s,
        grid_shape=solved.shape,
        target=spec.sampling.target,
        **figures,
    )


def build(
    spec: PlanSpec,
    rig: Rig,
    *,
    where: str = "plan",
    bounds: bool = False,
    text: bytes | None = None,
    placed: FloatArray | None = None,
    start: FloatArray | None = None,
) -> Plan:
    """The ordered, timed plan (`ConfigError` if the rig can reach none of it).

    ``bounds``: also compute the figures the benchmarks compare against, the
    generation-order duration (a second choice of solutions) and the MST lower bound
    (otherwise None in the summary). ``text``: the plan file's bytes, for the content
    hash (`gonio.planner.files.load_plan_source` gives them; default: the spec as YAML,
    `spec_text`). ``placed``: points already placed (generation order; the adaptive
    strategy's second pass, `gonio.planner.two_pass`) instead of the spec's; ``start``:
    the pose the motors leave from (default the rig's home). A fly plan
    (``sampling.strategy: fly``) is laid out by `gonio.planner.fly.build_fly` (no
    lower bounds)."""
    if spec.sampling.strategy == "fly" and placed is None:
        if spec.sampling.fly_options().segment == "theta_h_line":
            return fly.build_paths(spec, rig, where=where, text=text, start=start)
        return fly.build_fly(spec, rig, where=where, text=text, start=start)
    check_detector(spec, rig, where, text)
    coords, shape = place(spec, rig, where) if placed is None else (placed, None)
    home = rig.home if start is None else np.asarray(start, dtype=np.float64)
    solved = solve(spec, rig, where, coords, shape)
    ordered = order_targets(spec, rig, where, solved, home)
    started = time.perf_counter()
    figures = lower_bounds(rig, solved, ordered, home) if bounds else {}
    bound_wall_s = time.perf_counter() - started if bounds else None
    chosen = solved.sel[ordered.given[ordered.order]]
    order = np.searchsorted(solved.sel, chosen)  # positions in generation order
    wi, wo = rig.forward(ordered.angles, rig.alignment)  # the pair the chosen pose measures
    times = timing(spec, rig, wi, wo, ordered.travel)
    return Plan(
        spec=spec,
        rig=rig,
        coordinate_names=spec.coordinates(),
        coords=coords[solved.kept][order],
        generated=solved.kept[order],
        wi=wi,
        wo=wo,
        angles=ordered.angles,
        exposure_s=times.exposure,
        averages=times.averages,
        travel_s=ordered.travel,
        arrival_s=times.arrival,
        summary=summarize(spec, rig, solved, ordered, times, figures),
        plan_text=spec_text(spec) if text is None else text,
        ordering=ordered.ordering,
        ordering_s=ordered.ordering_s,
        bound_wall_s=bound_wall_s,
    )
