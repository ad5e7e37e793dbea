"""The read model of a run shared by ``gonio serve`` and ``gonio watch``: a run file
followed as it grows (`LiveRun`), and what is shown of it (`overview`, `points`).

`LiveRun` keeps one read-only connection to the run file and reads, at each
`LiveRun.refresh`, only what was committed since the last one (the samples' columns
the views need, the new events); each read is one read transaction, so it sees a
consistent snapshot while ``gonio acquire`` writes (SQLite's WAL). What it holds is a
`gonio.store.read.Run` (the stored plan, the metadata, the events and sessions of
`gonio.store.read`), so the analysis (`gonio.analysis.calibrated`) works on it as on a
run opened whole. A run of a million samples opens in about a second this way.

State: ``running`` while a ``gonio acquire`` holds the run file's lock, ``paused`` if
it holds it and its last pause (a request, or a health condition) has not been resumed
yet; otherwise ``completed``, ``stopped`` (ended early, resumable), or ``fault`` (a
motor fault, an abort or a full disk: resumable too).
"""

from __future__ import annotations

import json
import math
import os
import sqlite3
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.analysis.calibrated import calibrate, is_level
from gonio.errors import GonioError
from gonio.planner.files import parse_plan
from gonio.planner.model import Plan
from gonio.store.journal import JournalError, check_version
from gonio.store.read import Event, Run, Session
from gonio.types import FloatArray

#: The sample columns the views read (besides the directions).
_COLUMNS = (
    "target", "counts", "counts_std", "n", "exposure_s", "started_s", "ended_s",
    "saturated", "wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z",
)  # fmt: skip
_INT = {"target", "n", "saturated"}
#: Events the event log lists (health readings and calibrations have views of their own).
LOGGED = frozenset(
    {"start", "resume", "pause", "fault", "retry", "skip", "second_pass", "range", "phase"}
)
#: Outcomes of a session that ended on a fault (resumable all the same).
_FAULTS = frozenset({"fault", "aborted", "journal"})
#: Samples whose wall time (UTC) the rate is measured over.
_RATE_WINDOW = 200


def _epoch(utc: str) -> float:
    try:
        return datetime.fromisoformat(utc).timestamp()
    except ValueError:
        return math.nan


def writer_holds(path: Path) -> bool:
    """Whether a process holds the run file's writer lock (``gonio acquire``'s flock),
    read from ``/proc/locks`` (nothing is locked or opened for writing to find out).
    Where that file is missing, False."""
    try:
        st = os.stat(path)
        text = Path("/proc/locks").read_text()
    except OSError:
        return False
    dev = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    return any(
        len(parts) > 5 and parts[1] == "FLOCK" and parts[5] == dev
        for parts in (line.split() for line in text.splitlines())
    )


@dataclass
class LiveRun:
    """A run file followed as it grows (see the module docstring). `JournalError` (one
    line) if ``path`` is not a readable run file."""

    path: Path
    run: Run = field(init=False)
    version: int = field(init=False, default=0)  # changes whenever something new is read
    _conn: sqlite3.Connection = field(init=False, repr=False)
    _columns: dict[str, list[np.ndarray]] = field(init=False, repr=False)
    _last_ended: float = field(init=False, default=-math.inf)
    _last_event: int = field(init=False, default=0)
    _data_version: int = field(init=False, default=-1)
    _plan_size: int = field(init=False, default=-1)
    _recent: list[tuple[float, float]] = field(init=False, default_factory=list)
    _writing: bool = field(init=False, default=False)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if not self.path.is_file():
            raise JournalError(f"{self.path}: no such run file")
        uri = f"{self.path.resolve().as_uri()}?mode=ro"
        self._conn = sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)
        try:
            check_version(self._conn, self.path)
        except sqlite3.DatabaseError as exc:
            self._conn.close()
            raise JournalError(f"{self.path}: not a readable run file: {exc}") from None
        self._columns = {}
        self._events: list[Event] = []
        self.refresh()

    def close(self) -> None:
        self._conn.close()

    def refresh(self) -> bool:
        """Read what was committed since the last refresh; whether anything was."""
        writing = writer_holds(self.path)
        try:
            changed = self._read()
        except sqlite3.DatabaseError as exc:
            raise JournalError(f"{self.path}: not a readable run file: {exc}") from None
        if changed or writing != self._writing:
            self._writing = writing
            self.version += 1
            return True
        return False

    def _read(self) -> bool:
        conn = self._conn
        data_version = int(conn.execute("PRAGMA data_version").fetchone()[0])
        if data_version == self._data_version:
            return False
        conn.execute("BEGIN")
        try:
            self._data_version = data_version
            size = conn.execute("SELECT length(value) FROM meta WHERE key = 'plan_file'")
            plan_size = int(size.fetchone()[0])
            meta_rows = None
            if plan_size != self._plan_size:  # the first read, or an adaptive second pass
                meta_rows = conn.execute("SELECT key, value FROM meta").fetchall()
            names = [r[1] for r in conn.execute("PRAGMA table_info(samples)")]
            wanted = [c for c in (*_COLUMNS, "utc") if c in names]
            quoted = ", ".join(f'"{c}"' for c in wanted)
            rows = conn.execute(
                f"SELECT {quoted} FROM samples WHERE ended_s > ? ORDER BY ended_s",
                (self._last_ended,),
            ).fetchall()
            events = conn.execute(
                "SELECT id, session, kind, target, t_s, utc, data FROM events WHERE id > ? "
                "ORDER BY id",
                (self._last_event,),
            ).fetchall()
            sessions = conn.execute(
                "SELECT id, started_utc, info, ended_utc, outcome FROM sessions ORDER BY id"
            ).fetchall()
        finally:
            conn.execute("COMMIT")
        if meta_rows is not None:
            self._meta(meta_rows, plan_size)
        self._add_samples(wanted, rows)
        for i, s, k, t, ts, u, d in events:
            self._events.append(Event(i, s, k, t, ts, u, MappingProxyType(json.loads(d))))
        if events:
            self._last_event = int(events[-1][0])
        self.run = Run(
            path=self.path,
            meta=self._meta_map,
            plan=self._plan,
            samples=MappingProxyType({k: self._column(k) for k in self._columns}),
            events=tuple(self._events),
            sessions=tuple(
                Session(i, st, MappingProxyType(json.loads(info)), en, out)
                for i, st, info, en, out in sessions
            ),
        )
        return True

    def _meta(self, rows: list[tuple[str, Any]], plan_size: int) -> None:
        meta: dict[str, Any] = {}
        plan_file = b""
        for key, value in rows:
            if key == "plan_file":
                plan_file = bytes(value)
            else:
                meta[key] = json.loads(value)
        self._meta_map: Mapping[str, Any] = MappingProxyType(meta)
        self._plan: Plan = parse_plan(plan_file, f"{self.path}#plan_file")
        self._plan_size = plan_size

    def _add_samples(self, names: list[str], rows: list[tuple[Any, ...]]) -> None:
        if not self._columns:
            self._columns = {n: [] for n in names if n != "utc"}
        if not rows:
            return
        cells = list(zip(*rows, strict=True))
        for n, values in zip(names, cells, strict=True):
            if n == "utc":
                continue
            if n in _INT:
                column = np.array(values, dtype=np.int64)
                self._columns[n].append(column.astype(np.bool_) if n == "saturated" else column)
            else:
                self._columns[n].append(
                    np.array([math.nan if v is None else v for v in values], dtype=np.float64)
                )
        self._last_ended = float(rows[-1][names.index("ended_s")])
        ended = rows[-1 - min(len(rows) - 1, _RATE_WINDOW) :]
        j, u = names.index("ended_s"), names.index("utc") if "utc" in names else -1
        if u >= 0:
            self._recent.extend((float(r[j]), _epoch(r[u])) for r in ended)
            self._recent = self._recent[-_RATE_WINDOW:]

    def _column(self, name: str) -> np.ndarray:
        parts = self._columns[name]
        if not parts:
            dtype = np.bool_ if name == "saturated" else np.int64 if name in _INT else np.float64
            return np.empty(0, dtype=dtype)
        if len(parts) > 1:
            parts[:] = [np.concatenate(parts)]
        return parts[0]

    # -- what is derived ---------------------------------------------------------------
    @property
    def writing(self) -> bool:
        """A ``gonio acquire`` holds the run file (as of the last refresh)."""
        return self._writing

    def state(self) -> str:
        """``running``, ``paused``, ``completed``, ``stopped`` or ``fault`` (module
        docstring)."""
        run = self.run
        if self._writing:
            current = run.sessions[-1].id if run.sessions else None
            for e in reversed(run.events):
                if e.session != current:
                    break
                if e.kind == "pause":
                    return "paused"
                if e.kind in ("resume", "start"):
                    return "running"
            return "running"
        if run.complete:
            return "completed"
        ended = [s for s in run.sessions if s.outcome is not None]
        if ended and ended[-1].outcome in _FAULTS:
            return "fault"
        return "stopped"

    def rate_per_s(self) -> float | None:
        """Samples per second of wall time over the last samples (None: too few)."""
        recent = [u for _, u in self._recent if math.isfinite(u)]
        if len(recent) < 3 or recent[-1] <= recent[0]:
            return None
        return (len(recent) - 1) / (recent[-1] - recent[0])


def _instrument_time(run: Run) -> float:
    times = [e.t_s for e in run.events]
    ended = run.samples["ended_s"]
    lo = min(times[0] if times else math.inf, float(ended.min()) if len(ended) else math.inf)
    hi = max(times[-1] if times else -math.inf, float(ended.max()) if len(ended) else -math.inf)
    return float(hi - lo) if math.isfinite(lo) and math.isfinite(hi) else 0.0


def _per_target_s(plan: Plan) -> FloatArray:
    return np.asarray(
        plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages, np.float64
    )


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
    run, plan = live.run, live.run.plan
    measured, targets = len(run), len(plan)
    skipped = int(run.skipped.size)
    missing = run.missing()
    per_target = _per_target_s(plan)
    predicted_left = float(per_target[missing].sum())
    rate = live.rate_per_s()
    state = live.state()
    eta = None
    if state in ("running", "paused") and rate:
        eta = float(missing.size / rate)
    health_spec = plan.rig.spec.health
    health = [
        {
            "t_s": e.t_s,
            "count": e.data.get("count"),
            "temperatures_c": e.data.get("temperatures_c", {}),
            "voltages_v": e.data.get("voltages_v", {}),
            "problems": e.data.get("problems", []),
        }
        for e in run.of_kind("health")
    ]
    calibrations = run.of_kind("calibration")
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
    logged = [_event_line(e) for e in run.events if e.kind in LOGGED]
    stopped = state in ("stopped", "fault")
    return {
        "name": run.path.name,
        "version": live.version,
        "state": state,
        "plan": plan.spec.name,
        "rig": plan.rig.spec.name,
        "backend": run.meta.get("backend"),
        "fly": plan.is_fly,
        "targets": targets,
        "measured": measured,
        "skipped": skipped,
        "missing": int(missing.size),
        "progress": (measured + skipped) / targets if targets else 1.0,
        "instrument_time_s": _instrument_time(run),
        "predicted_s": float(plan.summary.total_s),
        "predicted_done_s": float(per_target.sum() - predicted_left),
        "predicted_left_s": predicted_left,
        "rate_per_s": rate,
        "eta_s": eta,
        "sessions": len(run.sessions),
        "outcome": run.sessions[-1].outcome if run.sessions else None,
        "health": health[-500:],
        "health_limits": {
            "max_temperature_c": health_spec.max_temperature_c,
            "min_voltage_v": health_spec.min_voltage_v,
            "max_voltage_v": health_spec.max_voltage_v,
        },
        "calibrations": cal[-500:],
        "events": logged[-events:],
        "events_total": len(logged),
        "resume": f"gonio acquire --resume {run.path}" if stopped else None,
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


def points(
    live: LiveRun, *, limit: int = 20_000, pending: int = 5_000, plane_deg: float = 5.0
) -> dict[str, Any]:
    """The samples on the hemisphere (at most ``limit``, decimated on time order with
    the newest kept), the plan's targets still to measure (at most ``pending``), and
    the in-plane samples (ωo within ``plane_deg`` of the plane of incidence) with their
    BRDF and 1σ: JSON values, rounded for size. The value is the BRDF (sr⁻¹) once the
    run has a calibration, else the reading per second of exposure."""
    run, plan = live.run, live.run.plan
    n = len(run)
    pick = _pick(n, limit, newest=min(500, limit // 4))
    sub = _subset(run, pick)
    wi, wo = sub.directions()
    try:
        cal = calibrate(sub)
        value, sigma, unit = cal.brdf, cal.sigma, "sr⁻¹"
    except GonioError:
        exposure = np.maximum(sub.samples["exposure_s"], 1e-12)
        value, unit = sub.samples["counts"] / exposure, "per s"
        sigma = np.nan_to_num(sub.samples["counts_std"], nan=0.0) / exposure
    xy = _rotated(wi, wo)
    missing = run.missing()
    grey = missing[_pick(missing.size, pending, newest=0)]
    gxy = _rotated(plan.wi[grey], plan.wo[grey]) if grey.size else np.empty((0, 2))
    theta_i = np.degrees(np.arccos(np.clip(wi[:, 2], -1.0, 1.0)))
    theta_o = np.degrees(np.arccos(np.clip(wo[:, 2], -1.0, 1.0)))
    sin_o = np.hypot(xy[:, 0], xy[:, 1])
    off_plane = np.degrees(np.arcsin(np.clip(np.abs(xy[:, 1]) / np.maximum(sin_o, 1e-12), 0, 1)))
    in_plane = np.flatnonzero((off_plane <= plane_deg) | (sin_o < 1e-6))
    signed = np.where(xy[in_plane, 0] >= 0, 1.0, -1.0) * theta_o[in_plane]
    finite = np.isfinite(value)
    return {
        "name": run.path.name,
        "version": live.version,
        "measured": n,
        "shown": int(pick.size),
        "unit": unit,
        "xy": np.round(xy, 4).ravel().tolist(),
        "value": [float(v) if f else None for v, f in zip(value.tolist(), finite, strict=True)],
        "pending_xy": np.round(gxy, 4).ravel().tolist(),
        "pending": int(missing.size),
        "in_plane": {
            "theta_o_deg": np.round(signed, 3).tolist(),
            "theta_i_deg": np.round(theta_i[in_plane], 2).tolist(),
            "value": [_finite(v) for v in value[in_plane].tolist()],
            "sigma": [_finite(v) for v in sigma[in_plane].tolist()],
        },
    }


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def _subset(run: Run, index: np.ndarray) -> Run:
    """``run`` with only the samples at ``index`` (the views' decimation)."""
    samples = {k: v[index] for k, v in run.samples.items()}
    return Run(
        path=run.path, meta=run.meta, plan=run.plan, samples=MappingProxyType(samples),
        events=run.events, sessions=run.sessions,
    )  # fmt: skip


def wall_now() -> float:
    """The wall clock (s since the epoch), for the views' ages."""
    return time.time()
