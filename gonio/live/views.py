"""What the views show of a run (`gonio.live.model.LiveRun`): its figures (`overview`:
state, progress, times, rate, ETA, health, calibrations, events) and its samples
(`points`: on the hemisphere, decimated, the targets still to measure, the in-plane
ones with their BRDF and 1σ), as JSON values for ``gonio serve``'s page and
``gonio watch``."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from gonio.analysis.calibrated import calibration_series, is_level
from gonio.errors import GonioError
from gonio.live.derived import Result, residuals, rounded
from gonio.live.model import LiveRun
from gonio.store.read import Event
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
        "backend": live.meta.get("backend"),
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
    of exposure. With ``derived`` (`gonio.live.derived`): each shown sample's residual
    against the fit, the fit's figures and the reconstruction's slice."""
    s = live.samples
    pick = _pick(len(s["target"]), limit, newest=min(500, limit // 4))
    value, sigma, unit = values(live, pick)
    wi = np.stack([s["wi_x"][pick], s["wi_y"][pick], s["wi_z"][pick]], axis=1)
    wo = np.stack([s["wo_x"][pick], s["wo_y"][pick], s["wo_z"][pick]], axis=1)
    xy = _rotated(wi, wo)
    plan, missing = live.plan, live.missing()
    gxy = np.empty((0, 2))
    if plan is not None and missing is not None and missing.size:
        grey = missing[_pick(missing.size, pending, newest=0)]
        gxy = _rotated(plan.wi[grey], plan.wo[grey])
    theta_i = np.degrees(np.arccos(np.clip(wi[:, 2], -1.0, 1.0)))
    theta_o = np.degrees(np.arccos(np.clip(wo[:, 2], -1.0, 1.0)))
    sin_o = np.hypot(xy[:, 0], xy[:, 1])
    off_plane = np.degrees(np.arcsin(np.clip(np.abs(xy[:, 1]) / np.maximum(sin_o, 1e-12), 0, 1)))
    in_plane = np.flatnonzero((off_plane <= plane_deg) | (sin_o < 1e-6))
    signed = np.where(xy[in_plane, 0] >= 0, 1.0, -1.0) * theta_o[in_plane]
    residual: list[float | None] | None = None
    if derived is not None and derived.model is not None:
        r = residuals(derived.model, wi, wo, value, sigma)
        residual = [rounded(v) for v in np.round(r, 3).tolist()]
    return {
        "name": live.path.name,
        "version": live.version,
        "measured": live.measured,
        "fit": None if derived is None else derived.summary(),
        "residual": residual,
        "slice": None if derived is None else derived.slice,
        "shown": int(pick.size),
        "unit": unit,
        "xy": np.round(xy, 4).ravel().tolist(),
        "value": [rounded(v) for v in value.tolist()],
        "pending_xy": np.round(gxy, 4).ravel().tolist(),
        "pending": max(live.info.targets - live.measured - live.skipped, 0),
        "in_plane": {
            "theta_o_deg": np.round(signed, 3).tolist(),
            "theta_i_deg": np.round(theta_i[in_plane], 2).tolist(),
            "value": [rounded(v) for v in value[in_plane].tolist()],
            "sigma": [rounded(v) for v in sigma[in_plane].tolist()],
        },
    }
