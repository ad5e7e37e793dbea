"""Fly plans: readings taken while one axis sweeps at constant velocity.

Layout (`build_fly`):

- Lines: segments laid out through anchors drawn in the parametrization, their velocity
  from the blur budget (`gonio.planner.fly.lines`).
- Thinning: the streamed readings thinned to the target density until the kept ones
  reach ``sampling.target`` (`gonio.planner.fly.thin`).
- Order: the segments are ordered by the existing ordering on their two commanded end
  poses (`order_jointly`, each segment's run-up and overrun poses its two candidates),
  then the direction of each is chosen exactly along that order (Viterbi,
  `gonio.planner.poses.choose`, on the move from one segment's end to the next one's
  start).

Timing model: a sweep is a move at rest to its run-up pose (trapezoidal, `TravelModel`),
the rig's ``settle_s``, the ramp up (v / a), the constant-velocity part ((m − 1) period
+ integration, m the readings streamed), the ramp down (v / a). The stop-and-go
comparison measures the same readings at the same poses in the same order: a move,
settle and one integration each.

Coverage: the figures of `gonio.planner.fly.coverage`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio import params
from gonio.config import spec_text
from gonio.planner.fly.coverage import coverage, reference
from gonio.planner.fly.limits import check_fly
from gonio.planner.fly.lines import Laid
from gonio.planner.fly.thin import THINNED, lay_out_thinned
from gonio.planner.model import FlyFigures, Plan, Summary, Sweeps
from gonio.planner.ordering import Joint, default_kicks, default_moves, order_jointly
from gonio.planner.poses import choose
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig
from gonio.types import FloatArray


def order_segments(
    spec: PlanSpec, rig: Rig, laid: Laid, home: FloatArray
) -> tuple[np.ndarray, np.ndarray, Joint, float]:
    """(order (S,), reversed (S,) in that order, the `Joint` result, the wall time it
    took, s): the existing ordering on the segments' two commanded end poses, then each
    segment's direction chosen exactly along the order (the move from one's end to the
    next one's start)."""
    started = time.perf_counter()
    start, stop = np.array(laid.start), np.array(laid.stop)
    n, axes = start.shape
    cand = np.stack([start, stop], axis=1)
    usable = np.ones((n, 2), dtype=np.bool_)
    joint = order_jointly(
        rig.travel, cand, usable, start, home, method="auto",
        max_moves=default_moves(n) if spec.max_moves is None else spec.max_moves,
        kicks=default_kicks(n) if spec.kicks is None else spec.kicks,
        seed=spec.sampling.seed, time_budget_s=spec.time_budget_s,
    )  # fmt: skip
    order = joint.order
    forward = np.concatenate([start[order], stop[order]], axis=1)
    backward = np.concatenate([stop[order], start[order]], axis=1)
    both = np.stack([forward, backward], axis=1)

    def between(p: FloatArray, q: FloatArray) -> FloatArray:
        return rig.travel.time(p[..., axes:], q[..., :axes])

    chosen, _ = choose(both, usable, np.concatenate([home, home]), between)
    reversed_ = ~np.all(chosen[:, :axes] == start[order], axis=1)
    return order, reversed_, joint, time.perf_counter() - started


def build_fly(
    spec: PlanSpec,
    rig: Rig,
    *,
    where: str = "plan",
    text: bytes | None = None,
    start: FloatArray | None = None,
) -> Plan:
    """The fly plan of ``spec`` on ``rig`` (module docstring): its readings as the
    plan's targets in measuring order (each at its mid-integration pose, ``arrival_s``
    its integration start, ``exposure_s`` the integration time) and its segments
    (`Plan.sweeps`). `ConfigError` when the rig reaches too few readings, or before
    anything is laid out when the plan asks more than the rig or this machine allows
    (`gonio.planner.fly.limits.check_fly`)."""
    check_fly(spec, rig, where)
    fly = spec.sampling.fly_options()
    home = rig.home if start is None else np.asarray(start, dtype=np.float64)
    ref = reference(spec, rig)
    laid = lay_out_thinned(spec, rig, where, ref)
    order, reversed_, joint, ordering_s = order_segments(spec, rig, laid, home)
    counts = np.array([len(m) for m in laid.mids], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    t_int, period, settle = fly.integration, fly.period_s, rig.spec.settle_s
    rows: dict[str, list[FloatArray]] = {k: [] for k in ("start", "entry", "exit", "stop")}
    velocity, cruise_at, firsts, mids, generated, arrival = [], [], [], [], [], []
    streamed: list[int] = []
    t, here, first = 0.0, home, 0
    moves_s = ramps_s = cruise_s = 0.0
    for s, back in zip(order.tolist(), reversed_.tolist(), strict=True):
        ends = [laid.start[s], laid.entry[s], laid.exit[s], laid.stop[s]]
        if back:
            ends = ends[::-1]
        for key, pose in zip(rows, ends, strict=True):
            rows[key].append(pose)
        move = float(rig.travel.time(here, ends[0])) + settle
        n, slots = int(counts[s]), laid.slots[s]
        last = int(slots[-1])
        cruise = last * period + t_int
        t += move + laid.ramp_s[s]
        velocity.append(-laid.velocity[s] if back else laid.velocity[s])
        cruise_at.append(t)
        firsts.append(first)
        index = np.arange(n)[::-1] if back else np.arange(n)
        mids.append(laid.mids[s][index])
        generated.append(offsets[s] + index)
        arrival.append(t + period * ((last - slots[::-1]) if back else slots))
        streamed.append(last + 1)
        t += cruise + laid.ramp_s[s]
        moves_s += move
        ramps_s += 2.0 * laid.ramp_s[s]
        cruise_s += cruise
        here, first = ends[3], first + n
    sweeps = Sweeps(
        start=np.array(rows["start"]), entry=np.array(rows["entry"]),
        exit=np.array(rows["exit"]), stop=np.array(rows["stop"]),
        velocity=np.array(velocity), first=np.array(firsts), count=counts[order],
        cruise_at_s=np.array(cruise_at), streamed=np.array(streamed, dtype=np.int64),
        period_s=period, integration_s=t_int,
    )  # fmt: skip
    speeds = np.degrees(np.abs(sweeps.velocity).max(axis=1))
    figures = {
        "lines": laid.lines, "smear_max_deg": math.degrees(max(laid.smear)),
        "velocity_min_deg_s": float(speeds.min()), "velocity_max_deg_s": float(speeds.max()),
        "cruise_s": cruise_s, "ramps_s": ramps_s, "moves_s": moves_s,
    }  # fmt: skip
    readings = Readings(np.concatenate(mids), np.concatenate(arrival), np.concatenate(generated))
    refused = {**laid.refused, THINNED: laid.readings - len(readings.angles)}
    return assemble(
        spec, rig, where, text, home, readings, sweeps, figures, total_s=t,
        requested=laid.requested, refused=refused, ordering_s=ordering_s, joint=joint, ref=ref,
    )  # fmt: skip


@dataclass(frozen=True)
class Readings:
    """A fly plan's targets in measuring order: their mid-integration poses (N, A) rad,
    their integration starts (N,) s and their generation order (N,); ``exposure_s`` and
    ``averages`` (N,) where some are stop-and-go targets (None: the fly integration,
    once)."""

    angles: FloatArray
    arrival_s: FloatArray
    generated: np.ndarray
    exposure_s: FloatArray | None = None
    averages: np.ndarray | None = None


def assemble(
    spec: PlanSpec, rig: Rig, where: str, text: bytes | None, home: FloatArray,
    readings: Readings, sweeps: Sweeps, figures: dict[str, Any], *, total_s: float,
    requested: int, refused: dict[str, int], ordering_s: float, joint: Joint,
    ref: FloatArray,
) -> Plan:  # fmt: skip
    """The fly plan of ``readings`` on ``sweeps`` (whose layout took ``total_s``): the
    targets' pairs and coordinates, their travel and exposure, the stop-and-go time of
    the same readings in the same order (a move, settle and one integration each), the
    coverage figures, and ``figures`` (the layout's own `FlyFigures` fields)."""
    fly = spec.sampling.fly_options()
    t_int, settle = fly.integration, rig.spec.settle_s
    angles, arrival_s = readings.angles, readings.arrival_s
    n_total = len(angles)
    exposure = np.full(n_total, t_int) if readings.exposure_s is None else readings.exposure_s
    averages = np.ones(n_total, dtype=np.int64) if readings.averages is None else readings.averages
    before = np.concatenate([[0.0], (arrival_s + exposure * averages)[:-1]])
    wi, wo = rig.forward(angles, rig.alignment)
    p = params.get(spec.parametrization)
    coords = p.forward_iso(wi, wo) if spec.isotropic else p.forward(wi, wo)
    previous = np.vstack([home[None, :], angles[:-1]])
    stop_and_go_s = float(rig.travel.time(previous, angles).sum()) + n_total * (settle + t_int)
    cover = coverage(spec, rig, where, coords, ref)
    fly_figures = FlyFigures(
        **figures, segments=len(sweeps), integration_s=t_int, period_s=fly.period_s,
        blur_deg=fly.blur, stop_and_go_s=stop_and_go_s, coverage_tv=cover.tv,
        coverage_tv_uniform=cover.tv_uniform, coverage_bins=cover.bins,
        streamed=int(sweeps.streamed.sum()), coverage_gap=cover.gap,
        coverage_gap_uniform=cover.gap_uniform,
    )  # fmt: skip
    result = joint.ordering
    dwell_s = n_total * t_int if readings.exposure_s is None else float((exposure * averages).sum())
    summary = Summary(
        requested=requested, invalid=0, refused=refused, kept=n_total,
        travel_s=total_s - dwell_s, dwell_s=dwell_s,
        moves=result.moves, max_moves=result.max_moves, kicks=result.kicks,
        kicks_kept=result.kicks_kept, max_kicks=result.max_kicks, stopped=result.stopped,
        time_cap_s=spec.time_budget_s, target=spec.sampling.target, fly=fly_figures,
    )  # fmt: skip
    return Plan(
        spec=spec, rig=rig, coordinate_names=spec.coordinates(), coords=coords,
        generated=readings.generated, wi=wi, wo=wo, angles=angles,
        exposure_s=exposure, averages=averages,
        travel_s=arrival_s - before, arrival_s=arrival_s, summary=summary,
        plan_text=spec_text(spec) if text is None else text, ordering=result, sweeps=sweeps,
        ordering_s=ordering_s,
    )  # fmt: skip
