"""Fly plans' thinning: the streamed readings thinned to the target density.

The detector streams every reading; the plan's targets are those kept with probability
min(1, ρ / (c ρ̂)), ρ the target density (uniform over the reach) and ρ̂ the streamed
one, both counted in a ``THIN_RADIUS`` ball, c the ``THIN_QUANTILE`` of ρ / ρ̂;
systematic along each segment. Segments are cut to their first and last kept reading
(`Sweeps.streamed` readings streamed on each). Lines are laid out
(`gonio.planner.fly.lines`) until the kept readings reach ``sampling.target``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from gonio.config import ConfigError
from gonio.planner.fly.lines import ANCHOR_GAP, Laid, box, lay_out, plan_coords, sweep_axis
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig
from gonio.types import FloatArray

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


def thin(spec: PlanSpec, rig: Rig, laid: Laid, ref: FloatArray) -> list[np.ndarray]:
    """The stream indices kept on each segment: reading i kept with probability
    q_i = min(1, ρ(x_i) / (c ρ̂(x_i))), ρ the target (uniform over the reach) and ρ̂ the
    streamed readings' density, both counted in a `THIN_RADIUS` ball about x_i; c the
    `THIN_QUANTILE` of ρ / ρ̂. Systematic sampling along each segment (a running sum
    of q, its offset drawn from the plan's seed) spaces the kept readings evenly."""
    mids = np.concatenate(laid.mids)
    bounds = box(spec)
    unit = (plan_coords(spec, rig, mids) - bounds[:, 0]) / (bounds[:, 1] - bounds[:, 0])
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


def lay_out_thinned(spec: PlanSpec, rig: Rig, where: str, ref: FloatArray) -> Laid:
    """Lines laid out until the readings the thinning keeps reach ``sampling.target``;
    each segment trimmed to its first and last kept reading."""
    target = spec.sampling.target
    if target is None:
        raise ConfigError(f"{where}: sampling.target: the fly strategy needs a target")
    laid = lay_out(spec, rig, where, Laid(gap=ANCHOR_GAP), math.ceil(THIN_GUESS * target))
    while True:
        kept = thin(spec, rig, laid, ref)
        laid.kept = int(sum(len(k) for k in kept))
        if laid.kept >= target:
            break
        more = math.ceil(laid.readings * (target / max(laid.kept, 1) - 1.0) * 1.05) + 1
        lay_out(spec, rig, where, laid, laid.readings + more)
    return _trimmed(spec, rig, laid, kept)


def _trimmed(spec: PlanSpec, rig: Rig, laid: Laid, kept: list[np.ndarray]) -> Laid:
    """The segments holding kept readings, each shortened to its first and last kept
    one (their ramps inside the checked run: commandable), ``slots`` the kept readings'
    stream indices from the new entry."""
    fly = spec.sampling.fly_options()
    j = sweep_axis(rig, fly)
    half = 0.5 * fly.integration
    out = Laid(
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
