"""The read model of a run shared by ``gonio serve`` and ``gonio watch``: a run file
followed as it grows (`LiveRun`), and what is shown of it (`overview`, `points`).

`LiveRun` keeps one read-only connection to the run file and reads, at each
`LiveRun.refresh`, only what was committed since the last one (the samples' columns
the views need, by target: the rowid; the new events); each read is one read
transaction, so it sees a consistent snapshot while ``gonio acquire`` writes (SQLite's
WAL), and it uses the journal's own types (`gonio.store.read.Event`, ``Session``) and
the analysis's calibration (`gonio.analysis.calibrated`). A large run (over
`FULL_LIMIT` samples) is read by a share of its targets plus every sample committed
since, and its stored plan (over `LAZY_PLAN_BYTES`) by its header at once and its
targets in another process: a run of a million samples opens in seconds, not minutes
(docs/results/live.md).

State: ``running`` while a ``gonio acquire`` holds the run file's lock, ``paused`` if
it holds it and its last pause (a request, or a health condition) has not been resumed
yet; otherwise ``completed``, ``stopped`` (ended early, resumable), or ``fault`` (a
motor fault, an abort or a full disk: resumable too).
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import sqlite3
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.analysis.calibrated import calibration_series, is_level
from gonio.errors import GonioError
from gonio.planner.files import parse_plan
from gonio.planner.model import Plan
from gonio.rig.model import Rig
from gonio.store.journal import JournalError, check_version
from gonio.store.read import Event, Session
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
#: A run of at most this many samples is read whole; a larger one about `KEPT` of them
#: (every k-th target) and every sample committed since.
FULL_LIMIT = 200_000
KEPT = 50_000
#: A stored plan larger than this (bytes; about 30 000 targets) is parsed in the
#: background; its header is read at once.
LAZY_PLAN_BYTES = 8_000_000
_HEAD_BYTES = 4_000_000


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


@dataclass(frozen=True)
class PlanInfo:
    """What the views need of the stored plan, from its header alone (cheap even for a
    plan of a million targets): its name, rig, number of targets, predicted total
    (s), whether it is a fly plan or an adaptive plan's survey."""

    name: str
    rig: Rig
    targets: int
    total_s: float
    fly: bool
    survey: bool

    @classmethod
    def of(cls, head: bytes, rig_text: str, where: str) -> PlanInfo:
        header: dict[str, Any] = {}
        for raw in head.split(b"\n")[1:]:
            if not raw.startswith(b"#"):
                break
            key, _, value = raw.decode("utf-8").removeprefix("#").strip().partition(":")
            if key in ("spec", "summary"):
                header[key] = json.loads(value)
        if "spec" not in header or "summary" not in header:
            raise JournalError(f"{where}: the stored plan has no readable header")
        spec, summary = header["spec"], header["summary"]
        sampling = spec.get("sampling", {})
        targets = int(summary["kept"])
        wanted = sampling.get("target")
        return cls(
            name=str(spec.get("name", "")),
            rig=Rig.from_yaml(where, raw=rig_text.encode("utf-8")),
            targets=targets,
            total_s=float(summary["travel_s"]) + float(summary["dwell_s"]),
            fly=sampling.get("strategy") == "fly",
            survey=sampling.get("strategy") == "adaptive"
            and wanted is not None
            and targets < int(wanted),
        )


@dataclass(frozen=True)
class PlanArrays:
    """What the views use of the stored plan's targets: each one's predicted time (s:
    the move into it, the settle, the exposures) and its (ωi, ωo)."""

    per_target_s: FloatArray
    wi: FloatArray
    wo: FloatArray

    @classmethod
    def of(cls, plan: Plan) -> PlanArrays:
        each = plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages
        return cls(np.asarray(each, np.float64), plan.wi, plan.wo)


def _parse_in_background(path: Path, out: Connection) -> None:
    """Send a large run's `PlanArrays` and its measured targets through ``out`` (None
    if the plan cannot be parsed): the work of another process."""
    os.nice(10)  # after the acquisition and the server
    uri = f"{path.resolve().as_uri()}?mode=ro"
    result: tuple[PlanArrays, np.ndarray] | None = None
    try:
        conn = sqlite3.connect(uri, uri=True, isolation_level=None)
        try:
            conn.execute("BEGIN")
            raw = conn.execute("SELECT value FROM meta WHERE key = 'plan_file'").fetchone()[0]
            plan = parse_plan(bytes(raw), f"{path}#plan_file")
            targets = [r[0] for r in conn.execute("SELECT target FROM samples")]
            conn.execute("COMMIT")
        finally:
            conn.close()
        result = (PlanArrays.of(plan), np.array(targets, dtype=np.int64))
    except (GonioError, sqlite3.DatabaseError):
        pass
    out.send(result)
    out.close()


@dataclass
class LiveRun:
    """A run file followed as it grows (see the module docstring). `JournalError` (one
    line) if ``path`` is not a readable run file.

    ``samples``: the samples' columns the views use, in commit order: every sample of a
    run of at most `FULL_LIMIT` when first read, else about `KEPT` of those already
    there (every k-th target) and every one committed since. ``measured``: how many
    the run holds. The stored plan itself (`plan`) is parsed once, in the background
    when it is large (its header, `info`, is read at once)."""

    path: Path
    version: int = field(init=False, default=0)  # changes whenever something new is read
    meta: Mapping[str, Any] = field(init=False)
    info: PlanInfo = field(init=False)
    samples: dict[str, np.ndarray] = field(init=False)
    measured: int = field(init=False, default=0)
    skipped: int = field(init=False, default=0)
    events: list[Event] = field(init=False, default_factory=list)
    sessions: tuple[Session, ...] = field(init=False, default=())
    _conn: sqlite3.Connection = field(init=False, repr=False)
    _parts: dict[str, list[np.ndarray]] = field(init=False, repr=False)
    _top: int = field(init=False, default=-1)  # the largest target read
    _retried_targets: set[int] = field(init=False, default_factory=set)
    _last_event: int = field(init=False, default=0)
    _data_version: int = field(init=False, default=-1)
    _plan_size: int = field(init=False, default=-1)
    _recent: list[tuple[float, float]] = field(init=False, default_factory=list)
    _writing: bool = field(init=False, default=False)
    _plan: PlanArrays | None = field(init=False, default=None)
    _done: np.ndarray | None = field(init=False, default=None)  # measured, per target
    _loader: tuple[BaseProcess, Connection] | None = field(init=False, default=None)
    _lock: threading.Lock = field(init=False, default_factory=threading.Lock)
    _load_next: bool = field(init=False, default=False)  # start the plan's loader

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if not self.path.is_file():
            raise JournalError(f"{self.path}: no such run file")
        self._conn = self._connect()
        try:
            check_version(self._conn, self.path)
        except sqlite3.DatabaseError as exc:
            self._conn.close()
            raise JournalError(f"{self.path}: not a readable run file: {exc}") from None
        self._parts = {}
        self.refresh()

    def _connect(self) -> sqlite3.Connection:
        uri = f"{self.path.resolve().as_uri()}?mode=ro"
        return sqlite3.connect(uri, uri=True, isolation_level=None, check_same_thread=False)

    def close(self) -> None:
        self._conn.close()

    def refresh(self) -> bool:
        """Read what was committed since the last refresh; whether anything was."""
        if self._load_next:
            self._start_loader()
        self._poll_loader()
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

    # -- reading -------------------------------------------------------------------------
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
            if plan_size != self._plan_size:  # the first read, or an adaptive second pass
                self._read_meta(conn, plan_size)
            names = [r[1] for r in conn.execute("PRAGMA table_info(samples)")]
            wanted = [c for c in (*_COLUMNS, "utc") if c in names]
            quoted = ", ".join(f'"{c}"' for c in wanted)
            first = not self._parts
            if first:  # one scan of the table: later reads seek by target (the rowid)
                count = conn.execute("SELECT count(*) FROM samples").fetchone()[0]
                top = conn.execute("SELECT max(target) FROM samples").fetchone()[0]  # the rowid
                self.measured, self._top = int(count), -1 if top is None else int(top)
            if first and self.measured > FULL_LIMIT:
                stride = -(-(self._top + 1) // KEPT)
                rows = conn.execute(
                    "WITH RECURSIVE k(t) AS (SELECT 0 UNION ALL SELECT t + ? FROM k WHERE t + ? "
                    f"<= ?) SELECT {quoted} FROM samples JOIN k ON target = k.t ORDER BY target",
                    (stride, stride, self._top),
                ).fetchall()
                newest = conn.execute(
                    "SELECT ended_s, utc FROM samples ORDER BY target DESC LIMIT ?",
                    (_RATE_WINDOW,),
                ).fetchall()
                self._recent = sorted((float(t), _epoch(u)) for t, u in newest)
            elif first:
                rows = conn.execute(f"SELECT {quoted} FROM samples ORDER BY ended_s").fetchall()
            else:
                # What was committed since: targets beyond the last one read (a plan is
                # measured in its order), and skipped targets measured again since.
                rows = conn.execute(
                    f"SELECT {quoted} FROM samples WHERE target > ? ORDER BY target",
                    (self._top,),
                ).fetchall()
                rows += self._retried(conn, quoted)
                self.measured += len(rows)
            if rows:
                self._top = max(self._top, max(int(r[0]) for r in rows))
            events = conn.execute(
                "SELECT id, session, kind, target, t_s, utc, data FROM events WHERE id > ? "
                "ORDER BY id",
                (self._last_event,),
            ).fetchall()
            sessions = conn.execute(
                "SELECT id, started_utc, info, ended_utc, outcome FROM sessions ORDER BY id"
            ).fetchall()
            for i, sn, k, t, ts, u, d in events:
                self.events.append(Event(i, sn, k, t, ts, u, MappingProxyType(json.loads(d))))
            if events:
                self._last_event = int(events[-1][0])
            retried = self._skipped(conn)
            if first:
                self._retried_targets = retried
            skips = {e.target for e in self.events if e.kind == "skip" and e.target is not None}
            self.skipped = len(skips) - len(retried)
        finally:
            conn.execute("COMMIT")
        self._add_samples(wanted, rows, track=not (first and self.measured > FULL_LIMIT))
        self.sessions = tuple(
            Session(i, st, MappingProxyType(json.loads(info)), en, out)
            for i, st, info, en, out in sessions
        )
        return True

    def _retried(self, conn: sqlite3.Connection, quoted: str) -> list[tuple[Any, ...]]:
        """The rows of skipped targets (at or below the last target read) measured since
        the last read (``gonio acquire --resume --retry-skipped``)."""
        skips = {e.target for e in self.events if e.kind == "skip" and e.target is not None}
        wanted = sorted(t for t in skips - self._retried_targets if t <= self._top)
        rows: list[tuple[Any, ...]] = []
        for k in range(0, len(wanted), 500):
            chunk = wanted[k : k + 500]
            marks = ", ".join("?" * len(chunk))
            rows += conn.execute(
                f"SELECT {quoted} FROM samples WHERE target IN ({marks})", chunk
            ).fetchall()
        self._retried_targets.update(int(r[0]) for r in rows)
        return rows

    def _skipped(self, conn: sqlite3.Connection) -> set[int]:
        """The skipped targets that were measured since (by a retry)."""
        skips = (e.target for e in self.events if e.kind == "skip" and e.target is not None)
        skipped = sorted(set(skips))
        measured: set[int] = set()
        for k in range(0, len(skipped), 500):
            chunk = skipped[k : k + 500]
            marks = ", ".join("?" * len(chunk))
            found = conn.execute(f"SELECT target FROM samples WHERE target IN ({marks})", chunk)
            measured.update(int(r[0]) for r in found)
        return measured

    def _read_meta(self, conn: sqlite3.Connection, plan_size: int) -> None:
        meta: dict[str, Any] = {}
        for key, value in conn.execute("SELECT key, value FROM meta WHERE key != 'plan_file'"):
            meta[key] = json.loads(value)
        self.meta = MappingProxyType(meta)
        rowid = conn.execute("SELECT rowid FROM meta WHERE key = 'plan_file'").fetchone()[0]
        with conn.blobopen("meta", "value", rowid, readonly=True) as blob:  # its start only
            head = blob.read(_HEAD_BYTES)
        where = f"{self.path}#plan_file"
        self.info = PlanInfo.of(bytes(head), str(meta.get("rig_text", "")), where)
        self._plan_size = plan_size
        with self._lock:
            self._plan, self._done = None, None
        if plan_size <= LAZY_PLAN_BYTES:
            self._load_plan(conn)
        else:  # another process, from the next refresh on (not competing with this one)
            self._load_next = True

    def _start_loader(self) -> None:
        """Parse the plan in another process (parsing holds an interpreter for seconds)."""
        self._load_next = False
        context = multiprocessing.get_context("spawn")
        mine, theirs = context.Pipe(duplex=False)
        process = context.Process(
            target=_parse_in_background, args=(self.path, theirs), daemon=True
        )
        process.start()
        theirs.close()
        self._loader = (process, mine)

    def _load_plan(self, conn: sqlite3.Connection) -> None:
        raw = conn.execute("SELECT value FROM meta WHERE key = 'plan_file'").fetchone()[0]
        plan = parse_plan(bytes(raw), f"{self.path}#plan_file")
        targets = np.array([r[0] for r in conn.execute("SELECT target FROM samples")], np.int64)
        self._install(PlanArrays.of(plan), targets)

    def _install(self, arrays: PlanArrays, targets: np.ndarray) -> None:
        done = np.zeros(len(arrays.per_target_s), dtype=np.bool_)
        done[targets] = True
        with self._lock:
            if self._done is not None:  # marked meanwhile by new samples
                done |= self._done[: len(done)]
            self._plan, self._done = arrays, done

    def _poll_loader(self) -> None:
        """Install what the background process parsed, once it sent it."""
        loader = self._loader
        if loader is None or not loader[1].poll():
            return
        process, conn = loader
        self._loader = None
        try:
            result = conn.recv()
        except (EOFError, OSError):
            result = None
        conn.close()
        process.join(1)
        if result is None:
            return  # the plan could not be parsed: the views go on with its header
        self._install(*result)
        self._data_version = -1

    def _add_samples(self, names: list[str], rows: list[tuple[Any, ...]], track: bool) -> None:
        if not self._parts:
            self._parts = {n: [] for n in names if n != "utc"}
            self.samples = {n: self._column(n) for n in self._parts}
        if not rows:
            return
        cells = list(zip(*rows, strict=True))
        for n, values in zip(names, cells, strict=True):
            if n == "utc":
                continue
            if n in _INT:
                column = np.array(values, dtype=np.int64)
                self._parts[n].append(column.astype(np.bool_) if n == "saturated" else column)
            else:
                self._parts[n].append(
                    np.array([math.nan if v is None else v for v in values], dtype=np.float64)
                )
        with self._lock:
            if self._done is not None:
                self._done[np.array(cells[names.index("target")], dtype=np.int64)] = True
        self.samples = {n: self._column(n) for n in self._parts}
        if track and "utc" in names:
            j, u = names.index("ended_s"), names.index("utc")
            self._recent.extend((float(r[j]), _epoch(r[u])) for r in rows[-_RATE_WINDOW:])
            self._recent = self._recent[-_RATE_WINDOW:]

    def _column(self, name: str) -> np.ndarray:
        parts = self._parts[name]
        if not parts:
            dtype = np.bool_ if name == "saturated" else np.int64 if name in _INT else np.float64
            return np.empty(0, dtype=dtype)
        if len(parts) > 1:
            parts[:] = [np.concatenate(parts)]
        return parts[0]

    # -- what is derived ---------------------------------------------------------------
    @property
    def plan(self) -> PlanArrays | None:
        """What the views use of the stored plan's targets, once parsed (None while a
        large one is parsed)."""
        return self._plan

    def missing(self) -> np.ndarray | None:
        """The targets not measured nor skipped, in the plan's order (None until the
        plan is parsed)."""
        with self._lock:
            if self._plan is None or self._done is None:
                return None
            left = ~self._done
        skipped = [e.target for e in self.events if e.kind == "skip" and e.target is not None]
        left[np.array(skipped, dtype=np.int64)] = False
        return np.flatnonzero(left)

    def of_kind(self, *kinds: str) -> list[Event]:
        return [e for e in self.events if e.kind in kinds]

    @property
    def complete(self) -> bool:
        done = bool(self.sessions) and self.sessions[-1].outcome == "completed"
        return done and not self.info.survey

    @property
    def writing(self) -> bool:
        """A ``gonio acquire`` holds the run file (as of the last refresh)."""
        return self._writing

    def state(self) -> str:
        """``running``, ``paused``, ``completed``, ``stopped`` or ``fault`` (module
        docstring)."""
        if self._writing:
            current = self.sessions[-1].id if self.sessions else None
            for e in reversed(self.events):
                if e.session != current:
                    break
                if e.kind == "pause":
                    return "paused"
                if e.kind in ("resume", "start"):
                    return "running"
            return "running"
        if self.complete:
            return "completed"
        ended = [s for s in self.sessions if s.outcome is not None]
        if ended and ended[-1].outcome in _FAULTS:
            return "fault"
        return "stopped"

    def rate_per_s(self) -> float | None:
        """Samples per second of wall time over the last samples (None: too few)."""
        recent = [u for _, u in self._recent if math.isfinite(u)]
        if len(recent) < 3 or recent[-1] <= recent[0]:
            return None
        return (len(recent) - 1) / (recent[-1] - recent[0])


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


def _values(live: LiveRun, index: np.ndarray) -> tuple[FloatArray, FloatArray, str]:
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
    live: LiveRun, *, limit: int = 20_000, pending: int = 5_000, plane_deg: float = 5.0
) -> dict[str, Any]:
    """The samples on the hemisphere (at most ``limit``, decimated on time order with
    the newest kept), the plan's targets still to measure (at most ``pending``; none
    while a large plan is parsed), and the in-plane samples (ωo within ``plane_deg`` of
    the plane of incidence) with their BRDF and 1σ: JSON values, rounded for size. The
    value is the BRDF (sr⁻¹) once the run has a calibration, else the reading per second
    of exposure."""
    s = live.samples
    pick = _pick(len(s["target"]), limit, newest=min(500, limit // 4))
    value, sigma, unit = _values(live, pick)
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
    return {
        "name": live.path.name,
        "version": live.version,
        "measured": live.measured,
        "shown": int(pick.size),
        "unit": unit,
        "xy": np.round(xy, 4).ravel().tolist(),
        "value": [_round(v) for v in value.tolist()],
        "pending_xy": np.round(gxy, 4).ravel().tolist(),
        "pending": max(live.info.targets - live.measured - live.skipped, 0),
        "in_plane": {
            "theta_o_deg": np.round(signed, 3).tolist(),
            "theta_i_deg": np.round(theta_i[in_plane], 2).tolist(),
            "value": [_round(v) for v in value[in_plane].tolist()],
            "sigma": [_round(v) for v in sigma[in_plane].tolist()],
        },
    }


def _round(v: float) -> float | None:
    """``v`` to 5 significant digits (None if not finite)."""
    return float(f"{v:.5g}") if math.isfinite(v) else None
