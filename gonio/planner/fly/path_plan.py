"""Fly plans of path lines (``fly.segment: theta_h_line``): lines along θh at fixed
(θd, φd), every axis following a streamed trajectory (`gonio.planner.fly.paths`).

Layout (`build_paths`):

- Lines: (θd, φd) drawn (scrambled Sobol, the plan's seed) over [0, π/2] × [0, π] from
  the density `line_density` (denser where the expected material varies more across the
  lines, per second of a line), each
  line's reachable segments laid out (`line_segments`) with their time law and their
  readings, until the readings reach ``sampling.target`` (whole lines).
- Order: the segments ordered by the existing ordering on their two end poses
  (`gonio.planner.fly.build.order_segments`: the order, then each segment's direction exactly
  along it); each then gets its trajectory and readings in the chosen direction.

Timing model: a segment is a move at rest to its first set-point (trapezoidal,
`TravelModel`), the rig's ``settle_s``, then the trajectory ((K − 1) set-point periods,
rest to rest). The stop-and-go comparison measures the same readings at the same poses
in the same order (a move, settle and one integration each).

Fill (``fly.fill``, a mixed plan): that many stop-and-go targets after the last
segment, where the lines leave the largest gaps (`fill_points`: greedy farthest points of
the coverage reference from the readings and from each other), ordered nearest first
from the last segment's end, each a move, the settle and the plan's exposure.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from drivers.trajectory import Trajectory
from gonio.config import ConfigError
from gonio.planner import placement, sampling
from gonio.planner.adaptive import Density, error_indicator, measure_density
from gonio.planner.fly.build import Readings, assemble, order_segments
from gonio.planner.fly.coverage import reference
from gonio.planner.fly.limits import check_fly
from gonio.planner.fly.lines import Laid, box, plan_coords
from gonio.planner.fly.paths import (
    DYNAMICS,
    PathReadings,
    PathSegment,
    checked_trajectory,
    line_segments,
    path_readings,
    rig_setpoint_period,
)
from gonio.planner.model import Plan, Sweeps
from gonio.planner.ordering import nearest_neighbour
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig, separation
from gonio.types import FloatArray

#: A segment's forward trajectory, its θh per set-point and its readings.
Forward = tuple[Trajectory, FloatArray, PathReadings]
#: Lines drawn per batch (a power of two for Sobol).
LINE_BATCH = 32
#: Lines drawn at most before a plan is refused for reaching too few readings.
MAX_LINES = 1 << 14
#: The refusal reason of streamed readings closer along θh than the step to a kept one.
CLOSE = "close"
#: The lines' density grid over (θd, φd): cells per coordinate.
LINE_CELLS = 32
#: The largest θd (rad) the default density's 1 / cos θd is taken at (beyond: constant).
GRAZING_THETA_D = math.radians(80.0)
#: A line's cost in seconds: a move and settle, then its θh extent at a typical speed.
LINE_OVERHEAD_S = 1.2
LINE_SPEED = math.radians(25.0)
#: The share of the lines spread uniformly over the cells the test measure reaches.
LINE_FLOOR = 0.25


def line_density(spec: PlanSpec, rig: Rig) -> Density:
    """The density of the lines over (θd, φd) (the unit square, `LINE_CELLS` a side).

    With an expected material (``fly.material``): the across-line error of a line
    spacing h is about h² times the second derivatives of log f across the lines (θd,
    φd: `gonio.planner.adaptive.error_indicator` on those two coordinates), summed along
    each line with the test measure's weight (`measure_density`); a line costs c (a move
    and its θh extent, `LINE_OVERHEAD_S`, `LINE_SPEED`). The error Σ w e² ρ^(−2) at a
    time Σ c ρ is least for ρ ∝ (w e² / c)^(1/3); a share `LINE_FLOOR` is uniform.
    Without one: ρ ∝ 1 / cos θd (up to `GRAZING_THETA_D`): the glossy and the matte
    scenes' errors sit at grazing θd (measured: studies/fly_trade.py)."""
    shape3 = (LINE_CELLS,) * 3
    w = measure_density(rig, "rusinkiewicz", True, shape3).reshape(shape3)
    reached = w.sum(axis=0) > 0  # (θd, φd) cells some test pair reaches
    uniform = reached / reached.sum()
    model = spec.sampling.fly_options().model()
    if model is None:
        theta_d = (np.arange(LINE_CELLS) + 0.5) / LINE_CELLS * 0.5 * math.pi
        weight = np.broadcast_to(
            1.0 / np.cos(np.minimum(theta_d, GRAZING_THETA_D))[:, None], reached.shape
        )
        optimal = np.where(reached, weight, 0.0)
    else:
        e = error_indicator(model.eval, "rusinkiewicz", True, shape3, dims=(1, 2))
        error = (w * e.reshape(shape3) ** 2).sum(axis=0)
        extent = (w > 0).sum(axis=0) * (0.5 * math.pi / LINE_CELLS)
        cost = LINE_OVERHEAD_S + extent / LINE_SPEED
        optimal = np.where(reached, error / cost, 0.0) ** (1.0 / 3.0)
    total = optimal.sum()
    shaped = optimal / total if total > 0 else uniform
    p = (1.0 - LINE_FLOOR) * shaped + LINE_FLOOR * uniform
    return Density((LINE_CELLS, LINE_CELLS), np.asarray(p.ravel(), dtype=np.float64))


def _min_step(blur_rad: float) -> float:
    """The least θh step (rad) between two targets of a line: half the blur budget."""
    return 0.5 * blur_rad


def lay_out_paths(
    spec: PlanSpec, rig: Rig, where: str, period_s: float
) -> tuple[list[PathSegment], list[Forward], int, int, dict[str, int]]:
    """(segments, each one's forward trajectory, θh and readings, lines, readings laid,
    refusals): lines drawn until their readings
    reach ``sampling.target``."""
    target = spec.sampling.target
    if target is None:
        raise ConfigError(f"{where}: sampling.target: the fly strategy needs a target")
    if not spec.isotropic:
        raise ConfigError(
            f"{where}: sampling.fly.segment: theta_h_line lines need an isotropic plan "
            "(isotropic: true); use detector_arc or light_arc"
        )
    fly = spec.sampling.fly_options()
    blur = math.radians(fly.blur)
    density = line_density(spec, rig)
    stream = sampling.Sequence("sobol", 3, spec.sampling.seed)
    segments: list[PathSegment] = []
    forward: list[Forward] = []
    refused: dict[str, int] = {}
    readings = lines = drawn = 0
    while readings < target:
        if drawn >= MAX_LINES:
            raise ConfigError(
                f"{where}: sampling.target: only {readings} of {target} readings are "
                f"reachable on {lines} lines after {MAX_LINES} lines drawn; lower the target "
                "or relax the rig's constraints"
            )
        unit = stream.draw(LINE_BATCH)
        drawn += LINE_BATCH
        points = density.points(unit) * np.array([0.5 * math.pi, math.pi])
        for theta_d, phi_d in points.tolist():
            laid = line_segments(rig, theta_d, phi_d, lines, spec.isotropic, refused)
            kept_any = False
            for seg in laid:
                out = checked_trajectory(rig, seg, blur, fly.integration, period_s, False)
                if out is None:
                    refused[DYNAMICS] = refused.get(DYNAMICS, 0) + len(seg.theta_h)
                    continue
                trajectory, _, theta = out
                got = path_readings(trajectory, theta, fly.rate_hz, fly.integration,
                                    _min_step(blur))  # fmt: skip
                segments.append(seg)
                forward.append((trajectory, theta, got))
                readings += len(got.slots)
                kept_any = True
            lines += int(kept_any)
            if readings >= target:
                break
    return segments, forward, lines, readings, refused


def build_paths(
    spec: PlanSpec,
    rig: Rig,
    *,
    where: str = "plan",
    text: bytes | None = None,
    start: FloatArray | None = None,
) -> Plan:
    """The fly plan of path lines of ``spec`` on ``rig`` (module docstring): its readings
    as the plan's targets in measuring order (each at its mid-integration pose,
    ``arrival_s`` its integration start) and its segments (`Plan.sweeps`, each with its
    trajectory). `ConfigError` when the rig reaches too few readings."""
    check_fly(spec, rig, where)
    fly = spec.sampling.fly_options()
    blur = math.radians(fly.blur)
    home = rig.home if start is None else np.asarray(start, dtype=np.float64)
    period_s = rig_setpoint_period(rig)
    segments, forward, lines, laid_readings, refused = lay_out_paths(spec, rig, where, period_s)
    ends = Laid(start=[s.poses[0] for s in segments], stop=[s.poses[-1] for s in segments])
    order, reversed_, joint, ordering_s = order_segments(spec, rig, ends, home)
    t_int, period, settle = fly.integration, fly.period_s, rig.spec.settle_s
    rows: dict[str, list[FloatArray]] = {"start": [], "stop": []}
    path_rows, path_first, path_count = [], [], []
    cruise_at, firsts, counts, mids, arrival, streamed = [], [], [], [], [], []
    t, here, first, at = 0.0, home, 0, 0
    moves_s = cruise_s = 0.0
    smear_max, speeds = 0.0, []
    for s, back in zip(order.tolist(), reversed_.tolist(), strict=True):
        if back:
            out = checked_trajectory(rig, segments[s], blur, t_int, period_s, True)
            if out is None:  # the forward law passed; the backward one is its mirror
                raise AssertionError("a segment's reversed trajectory failed the rig's checks")
            trajectory, _, theta = out
            got = path_readings(trajectory, theta, fly.rate_hz, t_int, _min_step(blur))
        else:
            trajectory, theta, got = forward[s]
        goals = trajectory.goals
        move = float(rig.travel.time(here, goals[0])) + settle
        t += move
        rows["start"].append(goals[0])
        rows["stop"].append(goals[-1])
        path_rows.append(goals)
        path_first.append(at)
        path_count.append(len(goals))
        cruise_at.append(t)
        firsts.append(first)
        counts.append(len(got.slots))
        mids.append(got.mids)
        arrival.append(t + period * got.slots)
        streamed.append(got.streamed)
        wi, wo = rig.forward(goals, rig.alignment)
        rate = np.maximum(separation(wi[1:], wi[:-1]), separation(wo[1:], wo[:-1]))
        smear_max = max(smear_max, float(rate.max()) / period_s * t_int)
        speeds.append(float(np.abs(trajectory.velocities()).max()))
        t += trajectory.duration_s
        moves_s += move
        cruise_s += trajectory.duration_s
        here, first, at = goals[-1], first + len(got.slots), at + len(goals)
    start_rows, stop_rows = np.array(rows["start"]), np.array(rows["stop"])
    sweeps = Sweeps(
        start=start_rows, entry=start_rows, exit=stop_rows, stop=stop_rows,
        velocity=np.zeros_like(start_rows), first=np.array(firsts), count=np.array(counts),
        cruise_at_s=np.array(cruise_at), streamed=np.array(streamed, dtype=np.int64),
        period_s=period, integration_s=t_int, path_first=np.array(path_first),
        path_count=np.array(path_count), path=np.concatenate(path_rows),
        path_period_s=period_s,
    )  # fmt: skip
    figures = {
        "lines": lines, "smear_max_deg": math.degrees(smear_max),
        "velocity_min_deg_s": math.degrees(min(speeds)),
        "velocity_max_deg_s": math.degrees(max(speeds)), "cruise_s": cruise_s,
        "ramps_s": 0.0, "moves_s": moves_s,
    }  # fmt: skip
    angles = np.concatenate(mids)
    ref = reference(spec, rig)
    readings = Readings(angles, np.concatenate(arrival), np.arange(len(angles)))
    refused = {**refused, CLOSE: int(sum(streamed)) - len(angles)}
    if fly.fill:
        readings, t = filled(spec, rig, readings, ref, here, t)
    return assemble(
        spec, rig, where, text, home, readings, sweeps, figures, total_s=t,
        requested=laid_readings + fly.fill, refused=refused, ordering_s=ordering_s,
        joint=joint, ref=ref,
    )  # fmt: skip


def fill_points(readings: FloatArray, ref: FloatArray, count: int) -> FloatArray:
    """``count`` of the reference points ``ref`` (unit box, reachable) farthest from the
    lines' ``readings`` (unit box) and from each other, farthest first (greedy)."""
    gap = cKDTree(readings).query(ref)[0]
    chosen = np.empty(min(count, len(ref)), dtype=np.int64)
    for n in range(len(chosen)):  # a loop per fill target: each depends on the last
        k = int(np.argmax(gap))
        chosen[n] = k
        gap = np.minimum(gap, np.linalg.norm(ref - ref[k], axis=1))
    return np.asarray(ref[chosen], dtype=np.float64)


def filled(
    spec: PlanSpec, rig: Rig, readings: Readings, ref: FloatArray, here: FloatArray, t: float
) -> tuple[Readings, float]:
    """``readings`` followed by ``fly.fill`` stop-and-go targets where the lines leave the
    largest gaps (`fill_points`), measured after the last sweep, nearest first (a move,
    settle, and the plan's exposure each); the time (s) they end at."""
    bounds = box(spec)
    unit = (plan_coords(spec, rig, readings.angles) - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    points = fill_points(unit, ref, spec.sampling.fly_options().fill)
    coords = bounds[:, 0] + points * (bounds[:, 1] - bounds[:, 0])
    _, wi, wo = placement.directions(spec, coords)
    solution = rig.solve(wi, wo, isotropic=spec.isotropic)
    poses = solution.angles[solution.ok]
    poses = poses[nearest_neighbour(rig.travel, poses, here)]
    previous = np.vstack([here[None, :], poses[:-1]])
    seconds, averages = spec.exposure.seconds, spec.exposure.averages
    moves = rig.travel.time(previous, poses) + rig.spec.settle_s
    dwell = seconds * averages
    arrival = t + np.cumsum(moves) + dwell * np.arange(len(poses))
    n, m = len(readings.angles), len(poses)
    fly_exposure = np.full(n, spec.sampling.fly_options().integration)
    out = Readings(
        np.vstack([readings.angles, poses]), np.concatenate([readings.arrival_s, arrival]),
        np.arange(n + m), np.concatenate([fly_exposure, np.full(m, seconds)]),
        np.concatenate([np.ones(n, dtype=np.int64), np.full(m, averages, dtype=np.int64)]),
    )  # fmt: skip
    end = float(arrival[-1] + dwell) if m else t
    return out, end
