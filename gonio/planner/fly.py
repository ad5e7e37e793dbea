"""Fly plans: readings taken while one axis sweeps at constant velocity.

Layout (`build_fly`):

- Anchors: points drawn (scrambled Sobol, the plan's seed) in the parametrization's
  coordinates, kept where the rig reaches them, each solved to its pose nearest home.
- Lines: through each anchor pose, the swept axis (the detector's last axis, or the
  light's) runs over its whole range, every other axis still.
- Velocity from the blur budget: a reading integrating for t smears its directions over
  r · v · t, with r the largest angular rate of ωi or ωo per radian of the swept axis
  along the line (computed on a `FINE_STEP` grid; 1 for an arc about an axis
  perpendicular to the pointing). v = min(blur / (r t), the axis's max velocity).
- Readings: every 1 / rate_hz seconds, i.e. every v / rate_hz radians along the line;
  kept where the pair measured at the reading's mid-integration pose is reachable at
  that very pose (`Rig.pose_reasons`, the refusal reasons counted). A run of kept
  readings is a segment, travelled at constant velocity; the axis accelerates before it
  and decelerates after it (trapezoidal, the axis's max acceleration), over poses that
  must be commandable (inside the limits, outside every keep-out box, checked on the
  `FINE_STEP` grid): readings whose ramp would leave them are refused ("ramp").
- Anchors nearer than ``ANCHOR_GAP`` (unit box) to a laid reading are skipped (the gap
  halved when a whole batch is): lines go where no reading passes yet.
- Thinning (`thin`): the detector streams every reading; the plan's targets are those
  kept with probability min(1, ρ / (c ρ̂)), ρ the target density (uniform over the
  reach) and ρ̂ the streamed one, both counted in a ``THIN_RADIUS`` ball, c the
  ``THIN_QUANTILE`` of ρ / ρ̂; systematic along each segment. Segments are cut to their
  first and last kept reading (`Sweeps.streamed` readings streamed on each).
- Lines are laid out, anchor after anchor, until the kept readings reach
  ``sampling.target`` (whole lines).
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

Coverage: the total-variation distance (half the L1 distance) between the readings'
histogram in the plan's coordinates (`COVERAGE_BINS` bins a coordinate over its box)
and that of `COVERAGE_POINTS` Sobol points kept where the rig reaches them (the uniform
target density); beside it, the same figure for a uniform stop-and-go plan of as many
targets (a second Sobol sequence), the noise floor of a uniform plan of that size. A
second figure: the largest empty ball (the largest distance, unit box, from a reference
point to its nearest reading), the same for the uniform plan.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from gonio import params
from gonio.config import ConfigError, spec_text
from gonio.planner import placement, sampling
from gonio.planner.model import FlyFigures, Plan, Summary, Sweeps
from gonio.planner.ordering import Joint, default_kicks, default_moves, order_jointly
from gonio.planner.poses import choose
from gonio.planner.schema import FlySpec, PlanSpec
from gonio.rig.constraints import separation
from gonio.rig.model import Reason, Rig
from gonio.types import FloatArray

#: Anchor points drawn per batch (a power of two for Sobol).
ANCHOR_BATCH = 64
#: Anchors drawn at most before a plan is refused for reaching too few readings.
MAX_ANCHORS = 1 << 16
#: Step (rad) of the grid on which a line's commandable poses and rates are checked.
FINE_STEP = math.radians(0.05)
#: Sobol points (kept where the rig reaches them) standing for the uniform density.
COVERAGE_POINTS = 1 << 15
#: Bins a coordinate for the coverage figure, by the number of coordinates.
COVERAGE_BINS = {3: 8, 4: 5}
#: The refusal reason of readings whose ramp would leave the commandable poses.
RAMP = "ramp"
#: The refusal reason of readings the coverage thinning left out (streamed, not targets).
THINNED = "thinned"
#: Radius (coordinates scaled to the unit box) of the balls in which the thinning
#: compares the streamed readings' density with the target density.
THIN_RADIUS = 0.06
#: The thinning keeps every reading where the streamed density is at most this quantile
#: of the target/streamed density ratio allows (higher: fewer readings, more uniform).
THIN_QUANTILE = 0.9
#: Readings streamed per kept one at first guess (laid out again until the target).
THIN_GUESS = 2.0
#: Anchors this near (unit box) to a laid reading are skipped at first (halved whenever
#: a whole batch is skipped): lines go where no reading passes yet.
ANCHOR_GAP = 0.05


@dataclass
class _Laid:
    """Segments laid out on the lines, generation order (rows per segment)."""

    start: list[FloatArray] = field(default_factory=list)
    entry: list[FloatArray] = field(default_factory=list)
    exit: list[FloatArray] = field(default_factory=list)
    stop: list[FloatArray] = field(default_factory=list)
    velocity: list[FloatArray] = field(default_factory=list)
    ramp_s: list[float] = field(default_factory=list)
    smear: list[float] = field(default_factory=list)  # rad
    mids: list[FloatArray] = field(default_factory=list)  # (n, A) each
    line: list[int] = field(default_factory=list)
    slots: list[np.ndarray] = field(default_factory=list)  # kept stream indices
    requested: int = 0
    anchors: int = 0  # anchors drawn
    kept: int = 0  # readings the thinning kept
    unit: list[FloatArray] = field(default_factory=list)  # readings' coords (unit box)
    gap: float = 0.0  # an anchor nearer than this to a reading is skipped
    readings: int = 0
    lines: int = 0
    refused: dict[str, int] = field(default_factory=dict)


def sweep_axis(rig: Rig, fly: FlySpec) -> int:
    """The index (in ``rig.axes``) of the axis a segment sweeps."""
    chain = rig.spec.detector if fly.segment == "detector_arc" else rig.spec.light
    return rig.axes.index(chain.axes[-1])


def _rate(rig: Rig, poses: FloatArray, ok: np.ndarray) -> float:
    """The largest angular rate of ωi or ωo (rad per rad of the swept axis) between
    consecutive commandable poses of a fine grid (1 where there are none)."""
    wi, wo = rig.forward(poses)
    step = np.maximum(separation(wi[1:], wi[:-1]), separation(wo[1:], wo[:-1])) / FINE_STEP
    both = ok[1:] & ok[:-1]
    return float(step[both].max()) if both.any() else 1.0


def _interval_ok(bad: np.ndarray, lo: float, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
    """Whether every fine-grid pose bracketing [x0, x1] (the swept axis's values) is
    commandable: ``bad`` the prefix count of non-commandable grid poses."""
    n = len(bad) - 1
    i0 = np.floor((x0 - lo) / FINE_STEP).astype(np.int64)
    i1 = np.ceil((x1 - lo) / FINE_STEP).astype(np.int64)
    inside = (i0 >= 0) & (i1 <= n - 1)
    i0c, i1c = np.clip(i0, 0, n - 1), np.clip(i1, 0, n - 1)
    return np.asarray(inside & (bad[i1c + 1] - bad[i0c] == 0))


def lay_line(rig: Rig, fly: FlySpec, anchor: FloatArray, laid: _Laid, line: int) -> None:
    """Lay the segments of the line through ``anchor`` (A,) into ``laid``."""
    j = sweep_axis(rig, fly)
    lo, hi = (float(x) for x in rig.limits[j])
    t_int, period = fly.integration, fly.period_s
    fine = lo + FINE_STEP * np.arange(math.floor((hi - lo) / FINE_STEP) + 1)
    poses = np.tile(anchor, (len(fine), 1))
    poses[:, j] = fine
    _, commandable = rig.pose_reasons(poses)
    bad = np.concatenate([[0], np.cumsum(~commandable)])
    rate = _rate(rig, poses, commandable)
    v = min(math.radians(fly.blur) / (rate * t_int), float(rig.velocity[j]))
    velocity = np.zeros_like(anchor)
    velocity[j] = v
    ramp_t, ramp = rig.travel.ramp(velocity)  # trapezoidal: v / a, then v² / 2a
    ramp_d = float(ramp[j])
    ds, half = v * period, 0.5 * v * t_int
    count = math.floor((hi - lo - 2.0 * half) / ds) + 1
    mids_x = lo + half + ds * np.arange(max(count, 0))
    mids = np.tile(anchor, (len(mids_x), 1))
    mids[:, j] = mids_x
    reasons, _ = rig.pose_reasons(mids)
    laid.requested += len(mids_x)
    for r in Reason:
        if r != Reason.OK:
            n = int(np.count_nonzero(reasons == r))
            laid.refused[r.label] = laid.refused.get(r.label, 0) + n
    ok = reasons == Reason.OK
    entry_ok = _interval_ok(bad, lo, mids_x - half - ramp_d, mids_x - half)
    exit_ok = _interval_ok(bad, lo, mids_x + half, mids_x + half + ramp_d)
    edges = np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    kept_any = False
    for a0, b0 in zip(starts.tolist(), ends.tolist(), strict=True):
        firsts = np.flatnonzero(entry_ok[a0 : b0 + 1])
        lasts = np.flatnonzero(exit_ok[a0 : b0 + 1])
        a1 = a0 + int(firsts[0]) if firsts.size else b0 + 1
        b1 = a0 + int(lasts[-1]) if lasts.size else a0 - 1
        if a1 <= b1:
            x0, x1 = mids_x[a1] - half, mids_x[b1] + half
            if not _interval_ok(bad, lo, np.array([x0]), np.array([x1]))[0]:
                a1, b1 = b0 + 1, a0 - 1  # a keep-out box between readings: none kept
        kept = max(b1 - a1 + 1, 0)
        laid.refused[RAMP] = laid.refused.get(RAMP, 0) + (b0 - a0 + 1 - kept)
        if not kept:
            continue
        kept_any = True
        x0, x1 = mids_x[a1] - half, mids_x[b1] + half
        row = []
        for x in (x0 - ramp_d, x0, x1, x1 + ramp_d):
            pose = anchor.copy()
            pose[j] = x
            row.append(pose)
        laid.start.append(row[0])
        laid.entry.append(row[1])
        laid.exit.append(row[2])
        laid.stop.append(row[3])
        laid.velocity.append(velocity.copy())
        laid.ramp_s.append(ramp_t)
        laid.smear.append(rate * v * t_int)
        laid.mids.append(mids[a1 : b1 + 1])
        laid.line.append(line)
        laid.readings += kept
    laid.lines += int(kept_any)


def _bounds(spec: PlanSpec) -> FloatArray:
    p = params.get(spec.parametrization)
    return np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)


def _coords(spec: PlanSpec, rig: Rig, angles: FloatArray) -> FloatArray:
    """The plan's coordinates of the pairs measured at ``angles`` (N, A)."""
    p = params.get(spec.parametrization)
    wi, wo = rig.forward(angles)
    return np.asarray(p.forward_iso(wi, wo) if spec.isotropic else p.forward(wi, wo))


def reference(spec: PlanSpec, rig: Rig) -> FloatArray:
    """`COVERAGE_POINTS` Sobol points kept where the rig reaches them (the uniform
    target density), scaled to the unit box."""
    bounds = _bounds(spec)
    d = len(bounds)
    stream = sampling.Sequence("sobol", d, spec.sampling.seed + 7919)
    points = sampling.to_box(stream.draw(COVERAGE_POINTS), bounds, np.ones(d))
    points = points[placement.kept_mask(spec, rig, points)]
    return np.asarray((points - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0]))


def lay_out(spec: PlanSpec, rig: Rig, where: str, laid: _Laid, until: int) -> _Laid:
    """Lines through anchors drawn in the parametrization (the plan's Sobol stream,
    continued after ``laid.anchors``) until ``until`` readings are laid."""
    target = spec.sampling.target
    if target is None:
        raise ConfigError(f"{where}: sampling.target: the fly strategy needs a target")
    fly = spec.sampling.fly_options()
    bounds = _bounds(spec)
    stream = sampling.Sequence("sobol", len(bounds), spec.sampling.seed)
    for _ in range(laid.anchors // ANCHOR_BATCH):
        stream.draw(ANCHOR_BATCH)  # continue the anchors already drawn
    scale = bounds[:, 1] - bounds[:, 0]
    while laid.readings < until:
        if laid.anchors >= MAX_ANCHORS:
            raise ConfigError(
                f"{where}: sampling.target: only {laid.kept or laid.readings} of {target} "
                f"readings are reachable on {laid.lines} sweeps after {MAX_ANCHORS} anchors; "
                "lower the target or relax the rig's constraints"
            )
        coords = sampling.to_box(stream.draw(ANCHOR_BATCH), bounds, np.ones(len(bounds)))
        laid.anchors += ANCHOR_BATCH
        valid, wi, wo = placement.directions(spec, coords)
        solution = rig.solve(wi, wo, isotropic=spec.isotropic)
        unit = (coords[valid][solution.ok] - bounds[:, 0]) / scale
        old = cKDTree(np.concatenate(laid.unit)) if laid.unit else None
        seen = len(laid.unit)
        laid_any = False
        for anchor, u in zip(solution.angles[solution.ok], unit, strict=True):
            near = [old] if old is not None else []
            if len(laid.unit) > seen:
                near.append(cKDTree(np.concatenate(laid.unit[seen:])))
            if any(tree.query(u)[0] < laid.gap for tree in near):
                continue  # readings already pass near this anchor
            before = len(laid.mids)
            lay_line(rig, fly, anchor, laid, laid.lines)
            if len(laid.mids) > before:
                laid_any = True
                new = np.concatenate(laid.mids[before:])
                laid.unit.append((_coords(spec, rig, new) - bounds[:, 0]) / scale)
            if laid.readings >= until:
                break
        if not laid_any:
            laid.gap *= 0.5  # anchors everywhere near readings: accept closer ones
    return laid


def thin(spec: PlanSpec, rig: Rig, laid: _Laid, ref: FloatArray) -> list[np.ndarray]:
    """The stream indices kept on each segment: reading i kept with probability
    q_i = min(1, ρ(x_i) / (c ρ̂(x_i))), ρ the target (uniform over the reach) and ρ̂ the
    streamed readings' density, both counted in a `THIN_RADIUS` ball about x_i; c the
    `THIN_QUANTILE` of ρ / ρ̂. Systematic sampling along each segment (a running sum
    of q, its offset drawn from the plan's seed) spaces the kept readings evenly."""
    mids = np.concatenate(laid.mids)
    bounds = _bounds(spec)
    unit = (_coords(spec, rig, mids) - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
    near = cKDTree(unit).query_ball_point(unit, THIN_RADIUS, return_length=True)
    want = cKDTree(ref).query_ball_point(unit, THIN_RADIUS, return_length=True)
    ratio = (np.asarray(want, dtype=np.float64) / len(ref)) / (
        np.asarray(near, dtype=np.float64) / len(unit)
    )
    scale = float(np.quantile(ratio, THIN_QUANTILE))
    q = np.minimum(1.0, ratio / max(scale, 1e-300))
    rng = np.random.default_rng(spec.sampling.seed)
    kept, at = [], 0
    for m in laid.mids:
        running = np.cumsum(q[at : at + len(m)]) + rng.random()
        steps = np.diff(np.floor(np.concatenate([[running[0] - q[at]], running])))
        kept.append(np.flatnonzero(steps > 0))
        at += len(m)
    return kept


def lay_out_thinned(spec: PlanSpec, rig: Rig, where: str, ref: FloatArray) -> _Laid:
    """Lines laid out until the readings the thinning keeps reach ``sampling.target``;
    each segment trimmed to its first and last kept reading."""
    target = spec.sampling.target
    if target is None:
        raise ConfigError(f"{where}: sampling.target: the fly strategy needs a target")
    laid = lay_out(spec, rig, where, _Laid(gap=ANCHOR_GAP), math.ceil(THIN_GUESS * target))
    while True:
        kept = thin(spec, rig, laid, ref)
        laid.kept = int(sum(len(k) for k in kept))
        if laid.kept >= target:
            break
        more = math.ceil(laid.readings * (target / max(laid.kept, 1) - 1.0) * 1.05) + 1
        lay_out(spec, rig, where, laid, laid.readings + more)
    return _trimmed(spec, rig, laid, kept)


def _trimmed(spec: PlanSpec, rig: Rig, laid: _Laid, kept: list[np.ndarray]) -> _Laid:
    """The segments holding kept readings, each shortened to its first and last kept
    one (their ramps inside the checked run: commandable), ``slots`` the kept readings'
    stream indices from the new entry."""
    fly = spec.sampling.fly_options()
    j = sweep_axis(rig, fly)
    half = 0.5 * fly.integration
    out = _Laid(
        requested=laid.requested, readings=laid.readings, refused=laid.refused,
        anchors=laid.anchors, kept=laid.kept,
    )  # fmt: skip
    lines = set()
    for s, k in enumerate(kept):
        if not len(k):
            continue
        v = float(laid.velocity[s][j])
        ramp_d = float(laid.entry[s][j] - laid.start[s][j])
        a, b = int(k[0]), int(k[-1])
        x0 = float(laid.mids[s][a, j]) - half * v
        x1 = float(laid.mids[s][b, j]) + half * v
        row = []
        for x in (x0 - ramp_d, x0, x1, x1 + ramp_d):
            pose = laid.entry[s].copy()
            pose[j] = x
            row.append(pose)
        out.start.append(row[0])
        out.entry.append(row[1])
        out.exit.append(row[2])
        out.stop.append(row[3])
        out.velocity.append(laid.velocity[s])
        out.ramp_s.append(laid.ramp_s[s])
        out.smear.append(laid.smear[s])
        out.mids.append(laid.mids[s][k])
        out.slots.append(k - a)
        out.line.append(laid.line[s])
        lines.add(laid.line[s])
    out.lines = len(lines)
    return out


def order_segments(
    spec: PlanSpec, rig: Rig, laid: _Laid, home: FloatArray
) -> tuple[np.ndarray, np.ndarray, Joint]:
    """(order (S,), reversed (S,) in that order, the `Joint` result): the existing
    ordering on the segments' two commanded end poses, then each segment's direction
    chosen exactly along the order (the move from one's end to the next one's start)."""
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
    return order, reversed_, joint


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
    bounds = _bounds(spec)
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


def check_integration(spec: PlanSpec, rig: Rig, where: str) -> None:
    """`ConfigError` unless the detector accepts the integration time."""
    lo, hi = rig.spec.detector.exposure_range_s
    t = spec.sampling.fly_options().integration
    if not lo <= t <= hi:
        raise ConfigError(
            f"{where}: sampling.fly.integration_s: {t:g} s is outside the detector's exposure "
            f"range [{lo:g}, {hi:g}] s (the rig file's detector.exposure_range_s)"
        )


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
    (`Plan.sweeps`). `ConfigError` when the rig reaches too few readings."""
    check_integration(spec, rig, where)
    fly = spec.sampling.fly_options()
    home = rig.home if start is None else np.asarray(start, dtype=np.float64)
    ref = reference(spec, rig)
    laid = lay_out_thinned(spec, rig, where, ref)
    started = time.perf_counter()
    order, reversed_, joint = order_segments(spec, rig, laid, home)
    ordering_s = time.perf_counter() - started
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
    angles = np.concatenate(mids)
    arrival_s = np.concatenate(arrival)
    n_total = len(angles)
    exposure = np.full(n_total, t_int)
    before = np.concatenate([[0.0], arrival_s[:-1] + t_int])
    travel_s = arrival_s - before
    wi, wo = rig.forward(angles)
    p = params.get(spec.parametrization)
    coords = p.forward_iso(wi, wo) if spec.isotropic else p.forward(wi, wo)
    sweeps = Sweeps(
        start=np.array(rows["start"]), entry=np.array(rows["entry"]),
        exit=np.array(rows["exit"]), stop=np.array(rows["stop"]),
        velocity=np.array(velocity), first=np.array(firsts), count=counts[order],
        cruise_at_s=np.array(cruise_at), streamed=np.array(streamed, dtype=np.int64),
        period_s=period, integration_s=t_int,
    )  # fmt: skip
    previous = np.vstack([home[None, :], angles[:-1]])
    stop_and_go_s = float(rig.travel.time(previous, angles).sum()) + n_total * (settle + t_int)
    cover = coverage(spec, rig, where, coords, ref)
    speeds = np.degrees(np.abs(sweeps.velocity).max(axis=1))
    figures = FlyFigures(
        lines=laid.lines, segments=len(sweeps), integration_s=t_int, period_s=period,
        blur_deg=fly.blur, smear_max_deg=math.degrees(max(laid.smear)),
        velocity_min_deg_s=float(speeds.min()), velocity_max_deg_s=float(speeds.max()),
        cruise_s=cruise_s, ramps_s=ramps_s, moves_s=moves_s, stop_and_go_s=stop_and_go_s,
        coverage_tv=cover.tv, coverage_tv_uniform=cover.tv_uniform, coverage_bins=cover.bins,
        streamed=int(sum(streamed)), coverage_gap=cover.gap,
        coverage_gap_uniform=cover.gap_uniform,
    )  # fmt: skip
    result = joint.ordering
    dwell_s = n_total * t_int
    refused = {**laid.refused, THINNED: laid.readings - n_total}
    summary = Summary(
        requested=laid.requested, invalid=0, refused=refused, kept=n_total,
        travel_s=t - dwell_s, dwell_s=dwell_s, ordering_s=ordering_s, moves=result.moves,
        max_moves=result.max_moves, kicks=result.kicks, kicks_kept=result.kicks_kept,
        max_kicks=result.max_kicks, stopped=result.stopped, time_cap_s=spec.time_budget_s,
        target=spec.sampling.target, fly=figures,
    )  # fmt: skip
    return Plan(
        spec=spec, rig=rig, coordinate_names=spec.coordinates(), coords=coords,
        generated=np.concatenate(generated), wi=wi, wo=wo, angles=angles,
        exposure_s=exposure, averages=np.ones(n_total, dtype=np.int64), travel_s=travel_s,
        arrival_s=arrival_s, summary=summary,
        plan_text=spec_text(spec) if text is None else text, ordering=result, sweeps=sweeps,
    )  # fmt: skip
