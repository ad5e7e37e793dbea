"""Fly plans' path lines: lines along θh at fixed (θd, φd), travelled by every axis at once.

An isotropic BRDF varies fast along θh (across the specular peak) and slowly along θd
and φd (Rusinkiewicz 1998's coordinates). A line along θh at fixed (θd, φd) samples the
fast direction densely; a coarse set of lines covers the slow ones.

- Geometry: with φh = 0, ωi = R_y(θh) d and ωo = R_y(θh) d̄ (d the difference vector at
  (θd, φd), d̄ = (−dx, −dy, dz)): both turn rigidly about the half-vector frame's y
  axis. On a `FINE_STEP` grid of θh from 0 (the mirror direction) to π/2, each pair is
  solved (every closed-form candidate, `Rig.candidates`) and one continuous branch is
  chosen along the line (`gonio.planner.poses.choose`, the least total travel).
- Segments: the runs of the line whose chosen poses measure their pair (`Rig.pose_reasons`
  OK) without a jump between neighbours (an axis turning more than `JUMP_PER_STEP` × the
  step: a branch change or a singular stretch), at least `MIN_POINTS` grid points long.
- Time law (`time_law`): a speed along the line v(θh) from rest to rest, limited by the
  blur budget (the measured directions' angular rate × v × integration ≤ blur), every
  axis's velocity (|dq/dθh| v ≤ its max) and a share `ACCELERATION_SHARE` of every axis's
  acceleration along the path (forward and backward passes on v², closed form).
- Trajectory (`trajectory_goals`): the poses at the time law sampled every set-point
  period of the rig's bus (`drivers.dynamixel.wire.setpoint_period`), checked against the
  limits, velocities and accelerations (`drivers.trajectory.check_trajectory`); a law
  that fails (the path's curvature) is slowed by `SLOWER` and tried again.
- Readings (`path_readings`): the detector streams from the trajectory's start, every
  1 / rate_hz; reading j's pose is the trajectory's at its mid-integration time. Readings
  closer along θh than the ``min_step`` to the previous kept one (the slow start and end)
  are not targets; every other reading is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.dynamixel import setpoint_period
from drivers.errors import LimitError
from drivers.trajectory import Trajectory, check_trajectory
from gonio.planner.poses import choose
from gonio.rig import Reason, Rig, separation
from gonio.types import FloatArray

#: Step (rad) of θh on which a line's poses and rates are solved.
FINE_STEP = math.radians(0.1)
#: An axis turning more than this many times the θh step between two grid points is a
#: jump (a branch change or a singular stretch): the line is cut there.
JUMP_PER_STEP = 10.0
#: The share of each axis's acceleration the time law spends along the path (the rest
#: is left to the path's curvature).
ACCELERATION_SHARE = 0.5
#: A segment spans at least this many grid points (shorter runs are refused, "short").
MIN_POINTS = 8
#: Factor on the speed and acceleration limits of a time law whose trajectory failed
#: the rig's checks (tried up to `TRIES` times).
SLOWER = 0.7
TRIES = 8
#: Refusal reasons of path readings.
JUMP = "jump"
SHORT = "short"
DYNAMICS = "dynamics"


def rig_setpoint_period(rig: Rig) -> float:
    """The set-point period (s) of the rig's bus (its motors and baud)."""
    return setpoint_period(len(rig.bus_axes()), rig.spec.bus.baud)


def line_pairs(theta_d: float, phi_d: float, theta_h: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(ωi, ωo) (M, 3) along θh (M,) at fixed (θd, φd), φh = 0 (see the module docstring)."""
    sd, cd = math.sin(theta_d), math.cos(theta_d)
    dx, dy, dz = sd * math.cos(phi_d), sd * math.sin(phi_d), cd
    c, s = np.cos(theta_h), np.sin(theta_h)
    wi = np.stack([c * dx + s * dz, np.full_like(c, dy), -s * dx + c * dz], axis=-1)
    wo = np.stack([-c * dx + s * dz, np.full_like(c, -dy), s * dx + c * dz], axis=-1)
    return wi, wo


@dataclass(frozen=True)
class PathSegment:
    """A reachable run of one line: θh (M,) increasing, the chosen poses (M, A) rad."""

    line: int
    theta_d: float
    phi_d: float
    theta_h: FloatArray
    poses: FloatArray


def line_segments(
    rig: Rig, theta_d: float, phi_d: float, line: int, isotropic: bool, refused: dict[str, int]
) -> list[PathSegment]:
    """The reachable segments of the line at (θd, φd); refusals counted per grid point."""
    theta_h = FINE_STEP * np.arange(math.floor(0.5 * math.pi / FINE_STEP) + 1, dtype=np.float64)
    wi, wo = line_pairs(theta_d, phi_d, theta_h)
    cand, _ = rig.candidates(wi, wo, isotropic=isotropic)
    ok_cand = np.ones(cand.shape[:2], dtype=np.bool_)
    flat = cand.reshape(-1, cand.shape[2])
    _, commandable = rig.pose_reasons(flat)
    ok_cand &= commandable.reshape(cand.shape[:2])
    any_ok = ok_cand.any(axis=1)
    out: list[PathSegment] = []
    edges = np.diff(np.concatenate([[0], any_ok.astype(np.int8), [0]]))
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        poses, _ = choose(cand[a:b], ok_cand[a:b], cand[a, int(np.argmax(ok_cand[a]))],
                          rig.travel.time)  # fmt: skip
        reasons, _ = rig.pose_reasons(poses)
        good = reasons == Reason.OK
        for r in Reason:
            if r != Reason.OK:
                refused[r.label] = refused.get(r.label, 0) + int(np.count_nonzero(reasons == r))
        step = np.abs(np.diff(poses, axis=0)).max(axis=1) if len(poses) > 1 else np.zeros(0)
        cut = np.concatenate([step > JUMP_PER_STEP * FINE_STEP, [False]])
        refused[JUMP] = refused.get(JUMP, 0) + int(np.count_nonzero(cut & good))
        # A run: consecutive good points with no jump to the next one.
        run_id = np.cumsum(np.concatenate([[0], (~good[:-1] | ~good[1:] | cut[:-1])]))
        for r_id in np.unique(run_id[good]).tolist():
            idx = np.flatnonzero((run_id == r_id) & good)
            if len(idx) < MIN_POINTS:
                refused[SHORT] = refused.get(SHORT, 0) + len(idx)
                continue
            out.append(PathSegment(line, theta_d, phi_d, theta_h[a + idx], poses[idx]))
    return out


def time_law(
    rig: Rig, seg: PathSegment, blur_rad: float, integration_s: float, slower: float = 1.0
) -> FloatArray:
    """The time (M,) s at which the segment passes each grid point, rest to rest (the
    module docstring); ``slower`` scales the speed and acceleration limits."""
    s, q = seg.theta_h, seg.poses
    ds = np.diff(s)
    dq = np.abs(np.diff(q, axis=0)) / ds[:, None]  # |dq/dθh| per interval (M − 1, A)
    wi, wo = rig.forward(q, rig.alignment)
    rate = np.maximum(separation(wi[1:], wi[:-1]), separation(wo[1:], wo[:-1])) / ds
    tiny = 1e-12
    v_axes = np.min(rig.velocity / np.maximum(dq, tiny), axis=1)
    v_blur = blur_rad / (np.maximum(rate, tiny) * integration_s)
    v_int = slower * np.minimum(v_axes, v_blur)
    a_int = slower * ACCELERATION_SHARE * np.min(rig.acceleration / np.maximum(dq, tiny), axis=1)
    v_node = np.minimum(np.concatenate([[0.0], v_int]), np.concatenate([v_int, [0.0]]))
    v_node[0] = v_node[-1] = 0.0
    reach = np.concatenate([[0.0], np.cumsum(2.0 * a_int * ds)])  # ∫ 2a ds from the start
    forward = reach + np.minimum.accumulate(v_node**2 - reach)
    back = reach[-1] - reach  # ∫ 2a ds to the end
    backward = back + np.minimum.accumulate((v_node**2 - back)[::-1])[::-1]
    v = np.sqrt(np.maximum(np.minimum(forward, backward), 0.0))
    both = v[1:] + v[:-1]
    # An interval between two nodes at rest (a segment of two): accelerate over half
    # of it and brake over the other half.
    rest = 2.0 * np.sqrt(ds / np.maximum(a_int, tiny))
    dt = np.where(both > tiny, 2.0 * ds / np.where(both > tiny, both, 1.0), rest)
    return np.concatenate([[0.0], np.cumsum(dt)])


def trajectory_goals(seg: PathSegment, t: FloatArray, period_s: float, backward: bool) -> tuple[
    FloatArray, FloatArray
]:  # fmt: skip
    """(set-points (K, A) rad every ``period_s`` from rest to rest, θh (K,) at each) of
    the segment at time law ``t``, forwards (θh rising) or ``backward``."""
    total = float(t[-1])
    k = math.ceil(total / period_s - 1e-9) + 1
    tau = np.minimum(period_s * np.arange(k), total)
    if backward:
        tau = total - tau
    theta = np.interp(tau, t, seg.theta_h)
    goals = np.stack([np.interp(theta, seg.theta_h, seg.poses[:, j])
                      for j in range(seg.poses.shape[1])], axis=1)  # fmt: skip
    return goals, theta


def checked_trajectory(
    rig: Rig, seg: PathSegment, blur_rad: float, integration_s: float, period_s: float,
    backward: bool,
) -> tuple[Trajectory, FloatArray, FloatArray] | None:  # fmt: skip
    """(the trajectory, the time law t (M,), its θh (K,) per set-point) of the segment,
    slowed until the rig's checks pass; None when they never do."""
    limits = {n: (float(lo), float(hi)) for n, (lo, hi) in zip(rig.axes, rig.limits, strict=True)}
    top_v = dict(zip(rig.axes, rig.velocity.tolist(), strict=True))
    top_a = dict(zip(rig.axes, rig.acceleration.tolist(), strict=True))
    slower = 1.0
    for _ in range(TRIES):
        t = time_law(rig, seg, blur_rad, integration_s, slower)
        goals, theta = trajectory_goals(seg, t, period_s, backward)
        trajectory = Trajectory(rig.axes, period_s, goals)
        try:
            check_trajectory(trajectory, limits, top_v, top_a)
        except LimitError:
            slower *= SLOWER
            continue
        return trajectory, t, theta
    return None


@dataclass(frozen=True)
class PathReadings:
    """The targets of one path sweep: their stream ``slots`` (R,), their poses ``mids``
    (R, A) rad at mid-integration, and ``streamed`` the stream's slots in all."""

    slots: np.ndarray
    mids: FloatArray
    streamed: int


def path_readings(
    trajectory: Trajectory, theta: FloatArray, rate_hz: float, integration_s: float,
    min_step: float,
) -> PathReadings:  # fmt: skip
    """The readings streamed along ``trajectory`` (θh ``theta`` (K,) at its set-points)
    kept as targets: each whose θh is at least ``min_step`` (rad) from the last kept."""
    period = 1.0 / rate_hz
    streamed = max(math.floor((trajectory.duration_s - integration_s) / period + 1e-9) + 1, 0)
    tau = period * np.arange(streamed, dtype=np.float64) + 0.5 * integration_s
    u = np.clip(tau / trajectory.period_s, 0.0, len(theta) - 1.0)
    theta_mid = np.interp(u, np.arange(len(theta)), theta)
    along = np.abs(theta_mid - theta[0])
    bins = np.floor(along / min_step).astype(np.int64)
    _, first = np.unique(bins, return_index=True)
    slots = np.sort(first).astype(np.int64)
    return PathReadings(slots, trajectory.at(tau[slots]), streamed)
