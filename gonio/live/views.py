"""What the views show of a run (`gonio.live.model.LiveRun`): its figures (`overview`:
state, progress, times, rate, ETA, health, calibrations, events) and its samples
(`points`: on the hemisphere, decimated, the targets still to measure, the in-plane
ones with their BRDF and 1σ), as JSON values for ``gonio serve``'s page and
``gonio watch``."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import yaml

from gonio.analysis import calibration_series, is_level
from gonio.brdf import BRDF
from gonio.errors import GonioError
from gonio.live.derived import Result, residuals, rounded
from gonio.live.model import LiveRun
from gonio.store import Event
from gonio.types import FloatArray

#: Events the event log lists (health readings and calibrations have views of their own).
LOGGED = frozenset(
    {"start", "resume", "pause", "stop", "fault", "retry", "skip", "second_pass", "range", "phase"}
)


def _instrument_time(live: LiveRun) -> float:
    ended = live.samples["ended_s"]
    times = [e.t_s for e in live.events]
    if len(ended):
        times += [float(ended.min()), float(ended.max())]
    return float(max(times) - min(times)) if times else 0.0


def _event_line(e: Event) -> dict[str, Any]:
    data = dict(e.data)
    data.pop("sim_state", None)
    return {"id": e.id, "kind": e.kind, "target": e.target, "t_s": e.t_s, "utc": e.utc, **data}


def _reference_rate(data: Mapping[str, Any]) -> float:
    ref, dark = data["reference"], data["dark"]
    counts = float(ref["value"]) - (0.0 if dark is None else float(dark["value"]))
    return counts / (1.0 if is_level(data) else float(ref["exposure_s"]))


def scene_name(meta: Mapping[str, Any]) -> str | None:
    """The stored scene's ``name`` (a simulated run; None on hardware or without one)."""
    text = meta.get("scene_text")
    if not text:
        return None
    try:
        scene = yaml.safe_load(text)
    except yaml.YAMLError:
        return None
    name = scene.get("name") if isinstance(scene, dict) else None
    return str(name) if name is not None else None


def overview(live: LiveRun, *, events: int = 100) -> dict[str, Any]:
    """The run's figures as JSON values: its state, progress, instrument time against the
    plan's prediction, rate, ETA (wall s), the motors' health readings against the rig's
    limits, the calibrations and the source drift, the last ``events`` logged events and
    the command that resumes it when it stopped."""
    info, plan = live.info, live.plan
    measured, targets, skipped = live.measured, info.targets, live.skipped
    left = max(targets - measured - skipped, 0)
    missing = live.missing()
    if plan is not None and missing is not None:
        per_target = plan.per_target_s
        predicted_left = float(per_target[missing].sum())
        predicted_done = float(per_target.sum()) - predicted_left
    else:  # a large plan still being parsed: in proportion
        predicted_left = info.total_s * left / max(targets, 1)
        predicted_done = info.total_s - predicted_left
    rate = live.rate_per_s()
    state = live.state()
    eta = float(left / rate) if state in ("running", "paused") and rate else None
    health_spec = info.rig.spec.health
    health = [
        {
            "t_s": e.t_s,
            "count": e.data.get("count"),
            "temperatures_c": e.data.get("temperatures_c", {}),
            "voltages_v": e.data.get("voltages_v", {}),
            "problems": e.data.get("problems", []),
        }
        for e in live.of_kind("health")
    ]
    calibrations = live.of_kind("calibration")
    first_rate = _reference_rate(calibrations[0].data) if calibrations else None
    cal = [
        {
            "t_s": e.t_s,
            "why": e.data.get("why"),
            "count": e.data.get("count"),
            "rate": _reference_rate(e.data),
            "drift": (_reference_rate(e.data) / first_rate - 1.0) if first_rate else None,
        }
        for e in calibrations
    ]
    logged = [_event_line(e) for e in live.events if e.kind in LOGGED]
    stopped = state in ("stopped", "fault")
    return {
        "name": live.path.name,
        "version": live.version,
        "state": state,
        "plan": info.name,
        "rig": info.rig.spec.name,
        "scene": scene_name(live.meta),
        "backend": live.meta.get("backend"),
        "isotropic": info.isotropic,
        "fly": info.fly,
        "targets": targets,
        "measured": measured,
        "skipped": skipped,
        "missing": left,
        "progress": (measured + skipped) / targets if targets else 1.0,
        "instrument_time_s": _instrument_time(live),
        "predicted_s": info.total_s,
        "predicted_done_s": predicted_done,
        "predicted_left_s": predicted_left,
        "rate_per_s": rate,
        "eta_s": eta,
        "sessions": len(live.sessions),
        "outcome": live.sessions[-1].outcome if live.sessions else None,
        "health": health[-500:],
        "health_limits": {
            "max_temperature_c": health_spec.max_temperature_c,
            "min_voltage_v": health_spec.min_voltage_v,
            "max_voltage_v": health_spec.max_voltage_v,
        },
        "calibrations": cal[-500:],
        "events": logged[-events:],
        "events_total": len(logged),
        "resume": f"gonio acquire --resume {live.path}" if stopped else None,
    }


def _rotated(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """ωo's (x, y) projection with the azimuth turned so ωi lies at φ = π (the plane of
    incidence along x, the mirror direction on +x)."""
    phi_i = np.arctan2(wi[:, 1], wi[:, 0])
    turn = np.pi - phi_i
    c, s = np.cos(turn), np.sin(turn)
    return np.stack([c * wo[:, 0] - s * wo[:, 1], s * wo[:, 0] + c * wo[:, 1]], axis=1)


def _pick(n: int, limit: int, newest: int) -> np.ndarray:
    """Indices of at most ``limit`` of ``n`` items in time order: evenly spaced, plus the
    last ``newest`` (so what was just measured always shows)."""
    if n <= limit:
        return np.arange(n)
    tail = np.arange(max(n - newest, 0), n)
    head = np.linspace(0, max(n - newest, 0) - 1, max(limit - newest, 0)).astype(np.int64)
    return np.unique(np.concatenate([head, tail]))


def values(live: LiveRun, index: np.ndarray) -> tuple[FloatArray, FloatArray, str]:
    """The samples' BRDF and 1σ (sr⁻¹) by the run's calibrations
    (`gonio.analysis.calibrated`), or without one the reading per second of exposure."""
    s = {k: v[index] for k, v in live.samples.items()}
    exposure = s["exposure_s"]
    counts, std = s["counts"], s["counts_std"]
    calibrations = tuple(live.of_kind("calibration"))
    try:
        series = calibration_series(calibrations)
    except GonioError:
        safe = np.maximum(exposure, 1e-12)
        return counts / safe, np.nan_to_num(std, nan=0.0) / safe, "per s"
    if is_level(calibrations[0].data):
        counts, std = counts * exposure, std * exposure
    wi = np.stack([s["wi_x"], s["wi_y"], s["wi_z"]], axis=1)
    wo = np.stack([s["wo_x"], s["wo_y"], s["wo_z"]], axis=1)
    t = 0.5 * (s["started_s"] + s["ended_s"])
    f, sigma = series.brdf(counts, std, s["n"], exposure, wi, wo, t)
    return np.asarray(f, np.float64), np.asarray(sigma, np.float64), "sr⁻¹"


def _degrees(w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Polar angle and azimuth (degrees, azimuth in [0, 360)) of unit vectors (N, 3)."""
    theta = np.degrees(np.arccos(np.clip(w[:, 2], -1.0, 1.0)))
    return theta, np.degrees(np.arctan2(w[:, 1], w[:, 0])) % 360.0


def incidence_groups(theta_i_deg: FloatArray, most: int = 8) -> tuple[FloatArray, float]:
    """Each in-plane sample's curve: its θi to the degree, or, when that makes more than
    ``most`` curves (a plan whose θi vary continuously), the middle of its 10° band; the
    curves' θi (degrees) and the width they stand for (1 or 10)."""
    theta: FloatArray = np.asarray(theta_i_deg, np.float64)
    whole: FloatArray = np.round(theta)
    if np.unique(whole).size <= most:
        return whole, 1.0
    band: FloatArray = np.floor(theta / 10.0) * 10.0 + 5.0
    return band, 10.0


def fit_curves(model: BRDF, theta_i_deg: FloatArray, *, n: int = 121) -> list[dict[str, Any]]:
    """The fitted model in the plane of incidence at each θi (degrees): f (sr⁻¹) at ``n``
    signed θo from −89° to 89° (positive on the mirror side), as JSON values."""
    if not len(theta_i_deg):
        return []
    ti = np.radians(np.asarray(theta_i_deg, np.float64))[:, None]
    to = np.radians(np.linspace(-89.0, 89.0, n))[None, :]
    shape = np.broadcast_shapes(ti.shape, to.shape)
    zero = np.zeros(shape)
    wi = np.stack([-np.sin(ti) + zero, zero, np.cos(ti) + zero], axis=-1).reshape(-1, 3)
    wo = np.stack([np.sin(to) + zero, zero, np.cos(to) + zero], axis=-1).reshape(-1, 3)
    f = np.asarray(model.eval(wi, wo), np.float64).reshape(shape)
    x = np.round(np.degrees(to[0]), 2).tolist()
    return [
        {"theta_i_deg": float(t), "theta_o_deg": x, "f": [rounded(v) for v in row.tolist()]}
        for t, row in zip(np.asarray(theta_i_deg, np.float64).tolist(), f, strict=True)
    ]


def points(
    live: LiveRun,
    *,
    limit: int = 20_000,
    pending: int = 5_000,
    plane_deg: float = 5.0,
    derived: Result | None = None,
) -> dict[str, Any]:
    """The samples on the hemisphere (at most ``limit``, decimated on time order with
    the newest kept), the plan's targets still to measure (at most ``pending``; none
    while a large plan is parsed), and the in-plane samples (ωo within ``plane_deg`` of
    the plane of incidence) with their BRDF and 1σ: JSON values, rounded for size. The
    value is the BRDF (sr⁻¹) once the run has a calibration, else the reading per second
    of exposure. Each shown sample: its pair's angles (θi, φi, θo, φo in degrees), its
    azimuth on the plot (``phi_deg``: φo turned so ωi lies at 180°, the mirror direction
    at 0°), its value and 1σ, its target, its place among the run's samples and its run
    time (s). With ``derived`` (`gonio.live.derived`): each shown sample's residual
    against the fit, the fit's figures, its curves in the plane of incidence at the
    in-plane samples' θi (`incidence_groups`) and the reconstruction's slice."""
    s = live.samples
    pick = _pick(len(s["target"]), limit, newest=min(500, limit // 4))
    value, sigma, unit = values(live, pick)
    wi = np.stack([s["wi_x"][pick], s["wi_y"][pick], s["wi_z"][pick]], axis=1)
    wo = np.stack([s["wo_x"][pick], s["wo_y"][pick], s["wo_z"][pick]], axis=1)
    xy = _rotated(wi, wo)
    plan, missing = live.plan, live.missing()
    gxy = np.empty((0, 2))
    g_theta = np.empty(0)
    if plan is not None and missing is not None and missing.size:
        grey = missing[_pick(missing.size, pending, newest=0)]
        gxy = _rotated(plan.wi[grey], plan.wo[grey])
        g_theta = _degrees(plan.wo[grey])[0]
    theta_i, phi_i = _degrees(wi)
    theta_o, phi_o = _degrees(wo)
    sin_o = np.hypot(xy[:, 0], xy[:, 1])
    off_plane = np.degrees(np.arcsin(np.clip(np.abs(xy[:, 1]) / np.maximum(sin_o, 1e-12), 0, 1)))
    in_plane = np.flatnonzero((off_plane <= plane_deg) | (sin_o < 1e-6))
    signed = np.where(xy[in_plane, 0] >= 0, 1.0, -1.0) * theta_o[in_plane]
    group, width = incidence_groups(theta_i[in_plane])
    residual: list[float | None] | None = None
    curves: list[dict[str, Any]] = []
    if derived is not None and derived.model is not None:
        r = residuals(derived.model, wi, wo, value, sigma)
        residual = [rounded(v) for v in np.round(r, 3).tolist()]
        curves = fit_curves(derived.model, np.unique(group))
    azimuth = np.degrees(np.arctan2(xy[:, 1], xy[:, 0])) % 360.0
    g_azimuth = np.degrees(np.arctan2(gxy[:, 1], gxy[:, 0])) % 360.0
    return {
        "name": live.path.name,
        "version": live.version,
        "measured": live.measured,
        "isotropic": live.info.isotropic,
        "fit": None if derived is None else derived.summary(),
        "fit_curves": curves,
        "residual": residual,
        "slice": None if derived is None else derived.slice,
        "shown": int(pick.size),
        "unit": unit,
        "theta_i_deg": np.round(theta_i, 2).tolist(),
        "phi_i_deg": np.round(phi_i, 2).tolist(),
        "theta_o_deg": np.round(theta_o, 2).tolist(),
        "phi_o_deg": np.round(phi_o, 2).tolist(),
        "phi_deg": np.round(azimuth, 2).tolist(),
        "value": [rounded(v) for v in value.tolist()],
        "sigma": [rounded(v) for v in sigma.tolist()],
        "target": s["target"][pick].astype(np.int64).tolist(),
        "index": pick.astype(np.int64).tolist(),
        "t_s": np.round(s["ended_s"][pick], 2).tolist(),
        "pending_theta_o_deg": np.round(g_theta, 2).tolist(),
        "pending_phi_deg": np.round(g_azimuth, 2).tolist(),
        "pending": max(live.info.targets - live.measured - live.skipped, 0),
        "in_plane": {
            "theta_o_deg": np.round(signed, 3).tolist(),
            "theta_i_deg": np.round(theta_i[in_plane], 2).tolist(),
            "group_deg": group.tolist(),
            "group_width_deg": width,
            "value": [rounded(v) for v in value[in_plane].tolist()],
            "sigma": [rounded(v) for v in sigma[in_plane].tolist()],
        },
    }
