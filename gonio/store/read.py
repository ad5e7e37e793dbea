"""Reading a run journal: `open_run(path)` gives the metadata, the stored plan, the
samples as numpy columns and the events, as one consistent snapshot, also of a run
that is still being written (the file is opened read-only, in one read transaction).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.planner.files import parse_plan
from gonio.planner.model import Plan
from gonio.store.journal import JournalError, check_version
from gonio.store.schema import ADDED_IN_2, FLOAT64, Column, commanded, read_back, samples_table
from gonio.types import FloatArray


@dataclass(frozen=True)
class Event:
    """One journaled event: its kind, the target it concerns (or None), the run time
    ``t_s`` (s), the UTC wall time and its data (JSON values)."""

    id: int
    session: int
    kind: str
    target: int | None
    t_s: float
    utc: str
    data: Mapping[str, Any]


@dataclass(frozen=True)
class Session:
    id: int
    started_utc: str
    info: Mapping[str, Any]
    ended_utc: str | None
    outcome: str | None


@dataclass(frozen=True)
class SweepRecord:
    """One journaled sweep of a fly plan (version 2): its index in the plan's sweeps,
    ``measured`` or ``abandoned``, its run times (s) and data (JSON values); its raw
    streams are read by `raw_streams`."""

    id: int
    session: int
    sweep: int
    outcome: str
    started_s: float
    ended_s: float
    data: Mapping[str, Any]


@dataclass(frozen=True)
class Run:
    """A run as stored. ``samples`` maps each column of the samples table to a numpy
    array (one entry per measured target, by target index); angles rad, times s,
    readings in the detector's counts."""

    path: Path
    meta: Mapping[str, Any]
    plan: Plan
    samples: Mapping[str, np.ndarray]
    events: tuple[Event, ...]
    sessions: tuple[Session, ...]
    sweeps: tuple[SweepRecord, ...] = ()
    _by_kind: dict[str, tuple[Event, ...]] = field(default_factory=dict, repr=False)

    @property
    def axes(self) -> tuple[str, ...]:
        return tuple(self.meta["axes"])

    @property
    def target(self) -> np.ndarray:
        """The plan index of each sample (int64)."""
        return self.samples["target"]

    def __len__(self) -> int:
        return len(self.samples["target"])

    def angles(self, which: str = "read_back") -> FloatArray:
        """(N, A) joint angles (rad) per sample, ``read_back`` or ``commanded``."""
        column = {"read_back": read_back, "commanded": commanded}[which]
        cols = [self.samples[column(a)] for a in self.axes]
        return np.stack(cols, axis=1) if cols else np.empty((0, 0))

    def directions(self) -> tuple[FloatArray, FloatArray]:
        """(ωi, ωo), each (N, 3), from the read-back angles (forward kinematics)."""
        s = self.samples
        wi = np.stack([s["wi_x"], s["wi_y"], s["wi_z"]], axis=1)
        wo = np.stack([s["wo_x"], s["wo_y"], s["wo_z"]], axis=1)
        return wi, wo

    def of_kind(self, *kinds: str) -> tuple[Event, ...]:
        """The events of these kinds, in order."""
        return tuple(e for e in self.events if e.kind in kinds)

    @property
    def skipped(self) -> np.ndarray:
        """Targets skipped (and not measured since), sorted."""
        skipped = {e.target for e in self.of_kind("skip") if e.target is not None}
        return np.array(sorted(skipped - set(self.target.tolist())), dtype=np.int64)

    def missing(self, *, include_skipped: bool = False) -> np.ndarray:
        """Targets of the plan not measured yet (nor skipped, unless asked), in the
        plan's order."""
        done = np.zeros(len(self.plan), dtype=np.bool_)
        done[self.target] = True
        if not include_skipped:
            done[self.skipped] = True
        return np.flatnonzero(~done)

    @property
    def complete(self) -> bool:
        """The last session ended the run (every target measured or skipped; for an
        adaptive plan, its second pass too)."""
        done = bool(self.sessions) and self.sessions[-1].outcome == "completed"
        return done and not self.plan.is_survey


def read_run(conn: sqlite3.Connection, path: Path) -> Run:
    """The run in an open connection (one read transaction: a consistent snapshot);
    `JournalError` (one line) if the file is not a readable run file (a table missing,
    the database damaged)."""
    try:
        return _read(conn, path)
    except sqlite3.DatabaseError as exc:
        raise JournalError(f"{path}: not a readable run file: {exc}") from None


def _read(conn: sqlite3.Connection, path: Path) -> Run:
    check_version(conn, path)
    conn.execute("BEGIN")
    try:
        meta_rows = conn.execute("SELECT key, value FROM meta").fetchall()
        cursor = conn.execute("SELECT * FROM samples ORDER BY target")
        names = [d[0] for d in cursor.description]
        rows = cursor.fetchall()
        events = conn.execute(
            "SELECT id, session, kind, target, t_s, utc, data FROM events ORDER BY id"
        ).fetchall()
        sessions = conn.execute(
            "SELECT id, started_utc, info, ended_utc, outcome FROM sessions ORDER BY id"
        ).fetchall()
        sweeps = (
            conn.execute(
                "SELECT id, session, sweep, outcome, started_s, ended_s, data FROM sweeps "
                "ORDER BY id"
            ).fetchall()
            if _has_table(conn, "sweeps")
            else []
        )
    finally:
        conn.execute("COMMIT")
    meta: dict[str, Any] = {}
    plan_file = b""
    for key, value in meta_rows:
        if key == "plan_file":
            plan_file = bytes(value)
        else:
            meta[key] = json.loads(value)
    plan = parse_plan(plan_file, f"{path}#plan_file")
    table = samples_table(meta["axes"], meta["coordinate_names"])
    return Run(
        path=path,
        meta=MappingProxyType(meta),
        plan=plan,
        samples=MappingProxyType(_columns(names, rows, table)),
        events=tuple(
            Event(i, s, k, t, ts, u, MappingProxyType(json.loads(d)))
            for i, s, k, t, ts, u, d in events
        ),
        sessions=tuple(
            Session(i, st, MappingProxyType(json.loads(info)), en, out)
            for i, st, info, en, out in sessions
        ),
        sweeps=tuple(
            SweepRecord(i, s, k, o, a, b, MappingProxyType(json.loads(d)))
            for i, s, k, o, a, b, d in sweeps
        ),
    )


def _has_table(conn: sqlite3.Connection, name: str) -> bool:
    found = conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", (name,))
    return found.fetchone() is not None


def raw_streams(run: Run, sweep_id: int) -> tuple[np.ndarray, FloatArray, np.ndarray]:
    """A journaled sweep's raw streams: the polls as (P, 2) request and reply times (s)
    and (P, A) positions (rad), and the stream's readings as a structured array
    (started_s, ended_s, value, std, saturated, device_t_s, received_s; NULL as NaN)."""
    conn = sqlite3.connect(f"{run.path.resolve().as_uri()}?mode=ro", uri=True)
    try:
        polls = conn.execute(
            "SELECT request_s, reply_s, positions FROM polls WHERE sweep_id = ? ORDER BY rowid",
            (sweep_id,),
        ).fetchall()
        stream = conn.execute(
            "SELECT started_s, ended_s, value, std, saturated, device_t_s, received_s FROM "
            "stream WHERE sweep_id = ? ORDER BY rowid",
            (sweep_id,),
        ).fetchall()
    finally:
        conn.close()
    times = np.array([(a, b) for a, b, _ in polls], dtype=np.float64).reshape(-1, 2)
    positions = np.array([json.loads(p) for _, _, p in polls], dtype=np.float64)
    names = ("started_s", "ended_s", "value", "std", "saturated", "device_t_s", "received_s")
    dtype = np.dtype([(n, np.float64) for n in names])
    readings = np.array([tuple(np.nan if c is None else c for c in r) for r in stream], dtype=dtype)
    return times, positions.reshape(len(polls), -1), readings


def _columns(
    names: list[str], rows: list[tuple[Any, ...]], table: Sequence[Column]
) -> dict[str, np.ndarray]:
    """The samples as numpy columns, each of its dtype in ``table`` (a column the table
    does not name reads as float64)."""
    dtypes = {c.name: c.dtype for c in table}
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(names):
        cells = [r[j] for r in rows]
        dtype = dtypes.get(name, FLOAT64)
        if dtype == FLOAT64:  # NULL (a spread the device did not give) reads as NaN
            out[name] = np.array([np.nan if c is None else c for c in cells], dtype=np.float64)
        else:
            out[name] = np.array(cells, dtype=dtype)
    for name in ADDED_IN_2:  # a version-1 run: no fly columns
        out.setdefault(name, np.full(len(rows), np.nan))
    return out


def open_run(path: str | Path) -> Run:
    """The run stored at ``path`` (read-only; a run still being written is read as it
    stands). `JournalError` (one line) if it is missing, not a gonio run file, or of a
    newer layout than this gonio reads."""
    path = Path(path)
    if not path.is_file():
        raise JournalError(f"{path}: no such run file")
    try:
        conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True, isolation_level=None)
    except sqlite3.Error as exc:
        raise JournalError(f"{path}: cannot open the run file: {exc}") from None
    try:
        return read_run(conn, path)
    finally:
        conn.close()
