"""Fly plans' lines: the segments laid out while one axis sweeps at constant velocity.

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
- Lines are laid out, anchor after anchor, until the readings laid reach the count asked
  (whole lines; `gonio.planner.fly.thin` asks until the kept ones reach
  ``sampling.target``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from gonio import params
from gonio.config import ConfigError
from gonio.planner import placement, sampling
from gonio.planner.fly_spec import FlySpec
from gonio.planner.schema import PlanSpec
from gonio.rig import Reason, Rig, separation
from gonio.types import FloatArray

#: Anchor points drawn per batch (a power of two for Sobol).
ANCHOR_BATCH = 64
#: Anchors drawn at most before a plan is refused for reaching too few readings.
MAX_ANCHORS = 1 << 16
#: Step (rad) of the grid on which a line's commandable poses and rates are checked.
FINE_STEP = math.radians(0.05)
#: The refusal reason of readings whose ramp would leave the commandable poses.
RAMP = "ramp"
#: Anchors this near (unit box) to a laid reading are skipped at first (halved whenever
#: a whole batch is skipped): lines go where no reading passes yet.
ANCHOR_GAP = 0.05


@dataclass
class Laid:
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
    wi, wo = rig.forward(poses, rig.alignment)
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


def lay_line(rig: Rig, fly: FlySpec, anchor: FloatArray, laid: Laid, line: int) -> None:
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


def box(spec: PlanSpec) -> FloatArray:
    """The plan's coordinate box (D, 2): the parametrization's bounds (isotropic or not)."""
    p = params.get(spec.parametrization)
    return np.asarray(p.iso_bounds if spec.isotropic else p.bounds, dtype=np.float64)


def plan_coords(spec: PlanSpec, rig: Rig, angles: FloatArray) -> FloatArray:
    """The plan's coordinates of the pairs measured at ``angles`` (N, A)."""
    p = params.get(spec.parametrization)
    wi, wo = rig.forward(angles, rig.alignment)
    return np.asarray(p.forward_iso(wi, wo) if spec.isotropic else p.forward(wi, wo))


def lay_out(spec: PlanSpec, rig: Rig, where: str, laid: Laid, until: int) -> Laid:
    """Lines through anchors drawn in the parametrization (the plan's Sobol stream,
    continued after ``laid.anchors``) until ``until`` readings are laid."""
    target = spec.sampling.target
    if target is None:
        raise ConfigError(f"{where}: sampling.target: the fly strategy needs a target")
    fly = spec.sampling.fly_options()
    bounds = box(spec)
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
                laid.unit.append((plan_coords(spec, rig, new) - bounds[:, 0]) / scale)
            if laid.readings >= until:
                break
        if not laid_any:
            laid.gap *= 0.5  # anchors everywhere near readings: accept closer ones
    return laid
