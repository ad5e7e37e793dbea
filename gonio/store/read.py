"""Reading a run journal: `open_run(path)` gives the metadata, the stored plan, the
samples as numpy columns and the events, as one consistent snapshot, also of a run
that is still being written (the file is opened read-only, in one read transaction,
leaving nothing beside it: `gonio.store.readonly`).
"""

from __future__ import annotations

import contextlib
import sqlite3
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.config import ConfigError
from gonio.planner import Plan, parse_plan
from gonio.store import checks, readonly
from gonio.store.journal import JournalError, check_version
from gonio.store.schema import (
    ADDED_IN_2,
    FLOAT64,
    INT64,
    OBJECT,
    Column,
    commanded,
    read_back,
    samples_table,
)
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
    `JournalError` (one line naming the file and the field) if the file is not a readable
    run file: a table missing, the database damaged, or a stored value not of the type
    or range the writer gives it (`gonio.store.checks`)."""
    with refusing(path):
        return _read(conn, path)


@contextlib.contextmanager
def refusing(path: Path) -> Iterator[None]:
    """Inside: a damaged file, a value the writer does not store (`checks.Bad`), a
    stored plan that does not parse or a lock held too long is `JournalError`, one line
    naming the file (and the field)."""
    try:
        yield
    except sqlite3.OperationalError as exc:
        if "locked" in str(exc) or "busy" in str(exc):
            raise JournalError(
                f"{path}: another process holds the run file locked ({_one_line(exc)}, "
                f"{readonly.BUSY_TIMEOUT_S:g} s waited); read it when that process is done"
            ) from None
        raise JournalError(f"{path}: not a readable run file: {_one_line(exc)}") from None
    except (sqlite3.DatabaseError, UnicodeDecodeError) as exc:  # a text stored damaged
        raise JournalError(f"{path}: not a readable run file: {_one_line(exc)}") from None
    except checks.Bad as exc:
        raise JournalError(f"{path}: not a readable run file: {exc}") from None
    except ConfigError as exc:  # the stored plan (its message names the run file)
        raise JournalError(str(exc)) from None


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())[:300]


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
    meta = decode_meta(meta_rows)
    plan_file = next((v for k, v in meta_rows if k == "plan_file"), b"")
    if not isinstance(plan_file, bytes):
        raise checks.Bad(f"meta.plan_file: expected the stored plan's bytes, got {plan_file!r:.40}")
    plan = parse_plan(plan_file, f"{path}#plan_file")
    check_plan(meta, plan)
    table = samples_table(meta["axes"], meta["coordinate_names"])
    samples = sample_columns(names, rows, table)
    check_targets(samples["target"], len(plan))
    check_samples(samples)
    return Run(
        path=path,
        meta=MappingProxyType(meta),
        plan=plan,
        samples=MappingProxyType(samples),
        events=tuple(event_of(row) for row in events),
        sessions=tuple(session_of(row) for row in sessions),
        sweeps=tuple(_sweep(row) for row in sweeps),
    )


def decode_meta(rows: Sequence[tuple[Any, Any]]) -> dict[str, Any]:
    """The ``meta`` table's rows (key, value) but the stored plan, decoded and checked
    (`checks.check_meta`); `checks.Bad` otherwise."""
    meta: dict[str, Any] = {}
    for key, value in rows:
        if not isinstance(key, str):
            raise checks.Bad(f"meta: expected text keys, got {key!r:.40}")
        if key != "plan_file":
            meta[key] = checks.json_value(value, f"meta.{key}")
    checks.check_meta(meta)
    return meta


def check_plan(meta: Mapping[str, Any], plan: Plan) -> None:
    """`checks.Bad` unless the run's axes and coordinates are its stored plan's."""
    if tuple(meta["axes"]) != plan.rig.axes:
        raise checks.Bad(
            f"meta.axes: expected the stored plan's rig axes {list(plan.rig.axes)}, "
            f"got {meta['axes']}"
        )
    if tuple(meta["coordinate_names"]) != plan.coordinate_names:
        raise checks.Bad(
            f"meta.coordinate_names: expected the stored plan's {list(plan.coordinate_names)}, "
            f"got {meta['coordinate_names']}"
        )


def check_targets(target: np.ndarray, targets: int) -> None:
    """`checks.Bad` unless every sample's target is one of the plan's ``targets``."""
    if target.size and (target.min() < 0 or target.max() >= targets):
        bad = int(target.min() if target.min() < 0 else target.max())
        raise checks.Bad(f"samples.target: {bad}; expected 0 … {targets - 1} (the plan's targets)")


def check_samples(samples: Mapping[str, np.ndarray]) -> None:
    """`checks.Bad` unless every sample's directions are unit vectors and its exposure
    positive (as the writer stores them; the analysis divides by the exposure)."""
    for side in ("wi", "wo"):
        v = np.stack([samples[f"{side}_{c}"] for c in "xyz"], axis=1)
        with np.errstate(over="ignore", invalid="ignore"):
            bad = ~(np.abs(np.einsum("ij,ij->i", v, v) - 1.0) <= checks.UNIT_TOLERANCE)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise checks.Bad(
                f"samples.{side}_x, _y, _z (row {i}): expected a unit vector, got {v[i].tolist()}"
            )
    exposure = samples["exposure_s"]
    if exposure.size and not (exposure > 0.0).all():
        i = int(np.flatnonzero(~(exposure > 0.0))[0])
        raise checks.Bad(
            f"samples.exposure_s (row {i}): expected a positive time, got {exposure[i]}"
        )


def event_of(row: tuple[Any, ...]) -> Event:
    i, s, k, t, ts, u, d = row
    where = f"events (id {i!r:.20})"
    kind = checks.text(k, f"{where}.kind")
    return Event(
        checks.integer(i, f"{where}.id"),
        checks.integer(s, f"{where}.session"),
        kind,
        checks.optional(checks.integer)(t, f"{where}.target"),
        checks.number(ts, f"{where}.t_s"),
        checks.text(u, f"{where}.utc"),
        MappingProxyType(checks.event_data(kind, d, f"{where}.data")),
    )


def session_of(row: tuple[Any, ...]) -> Session:
    i, st, info, en, out = row
    where = f"sessions (id {i!r:.20})"
    return Session(
        checks.integer(i, f"{where}.id"),
        checks.text(st, f"{where}.started_utc"),
        MappingProxyType(checks.mapping(checks.json_value(info, f"{where}.info"), f"{where}.info")),
        checks.optional(checks.text)(en, f"{where}.ended_utc"),
        checks.optional(checks.text)(out, f"{where}.outcome"),
    )


def _sweep(row: tuple[Any, ...]) -> SweepRecord:
    i, s, k, o, a, b, d = row
    where = f"sweeps (id {i!r:.20})"
    return SweepRecord(
        checks.integer(i, f"{where}.id"),
        checks.integer(s, f"{where}.session"),
        checks.integer(k, f"{where}.sweep"),
        checks.text(o, f"{where}.outcome"),
        checks.number(a, f"{where}.started_s"),
        checks.number(b, f"{where}.ended_s"),
        MappingProxyType(checks.mapping(checks.json_value(d, f"{where}.data"), f"{where}.data")),
    )


def _has_table(conn: sqlite3.Connection, name: str) -> bool:
    found = conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", (name,))
    return found.fetchone() is not None


def raw_streams(run: Run, sweep_id: int) -> tuple[np.ndarray, FloatArray, np.ndarray]:
    """A journaled sweep's raw streams: the polls as (P, 2) request and reply times (s)
    and (P, A) positions (rad), and the stream's readings as a structured array
    (started_s, ended_s, value, std, saturated, device_t_s, received_s; NULL as NaN).
    `JournalError` (one line) if the file is damaged or a value is not the writer's."""
    try:
        return _raw_streams(run, sweep_id)
    except sqlite3.DatabaseError as exc:
        raise JournalError(f"{run.path}: not a readable run file: {_one_line(exc)}") from None
    except (checks.Bad, ValueError, TypeError) as exc:
        raise JournalError(
            f"{run.path}: not a readable run file: sweep {sweep_id}'s streams: {_one_line(exc)}"
        ) from None


def _raw_streams(run: Run, sweep_id: int) -> tuple[np.ndarray, FloatArray, np.ndarray]:
    conn = readonly.connect(run.path)
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
    axes = len(run.axes)
    positions = np.array(
        [
            checks.vector(axes)(checks.json_value(p, "polls.positions"), "polls.positions")
            for _, _, p in polls
        ],
        dtype=np.float64,
    )
    names = ("started_s", "ended_s", "value", "std", "saturated", "device_t_s", "received_s")
    dtype = np.dtype([(n, np.float64) for n in names])
    readings = np.array([tuple(np.nan if c is None else c for c in r) for r in stream], dtype=dtype)
    return times, positions.reshape(len(polls), -1), readings


def sample_columns(
    names: list[str], rows: list[tuple[Any, ...]], table: Sequence[Column]
) -> dict[str, np.ndarray]:
    """The samples as numpy columns, each of its dtype in ``table`` (a column the table
    does not name reads as float64); `checks.Bad` for a column of the table missing (but
    those a version-1 file lacks) or a cell not of its column's type: a finite number
    where a number belongs (NULL only where the column allows it, read as NaN), a whole
    number where one does, a text where a text does."""
    missing = [c.name for c in table if c.name not in names and c.name not in ADDED_IN_2]
    if missing:
        raise checks.Bad(f"samples: column {missing[0]!r} missing")
    columns = {c.name: c for c in table}
    out: dict[str, np.ndarray] = {}
    by_column = list(zip(*rows, strict=True)) if rows else [()] * len(names)
    for name, cells_of in zip(names, by_column, strict=True):
        cells = list(cells_of)
        column = columns.get(name, Column(name, "REAL", FLOAT64, nullable=True))
        values = _column(cells, column)
        if values is None:
            _first_bad_cell(name, cells, column)
            raise checks.Bad(f"samples.{name}: expected values of type {column.sql}")
        out[name] = values
    for name in ADDED_IN_2:  # a version-1 run: no fly columns
        out.setdefault(name, np.full(len(rows), np.nan))
    return out


def _column(cells: list[Any], column: Column) -> np.ndarray | None:
    """The column's array, or None if a cell is not of its type."""
    # The cells' types, gathered once (SQLite gives exactly int, float, str, bytes or None).
    types = set(map(type, cells))
    null = {type(None)} if column.nullable else set()
    if column.dtype == OBJECT:
        return np.array(cells, dtype=object) if types <= {str} | null else None
    if column.dtype != FLOAT64:  # whole numbers (a bool column stores 0/1)
        if not types <= {int}:
            return None
        try:
            return np.array(cells, dtype=INT64).astype(column.dtype)
        except OverflowError:
            return None
    if not types <= {float, int, type(None)}:
        return None
    values = np.array(cells, dtype=np.float64)  # None reads as NaN
    finite = np.isfinite(values) if not column.nullable else ~np.isinf(values)
    return values if finite.all() else None


def _first_bad_cell(name: str, cells: list[Any], column: Column) -> None:
    """`checks.Bad` naming the first cell of ``name`` that is not of its column's type."""
    for i, cell in enumerate(cells):
        if cell is None and column.nullable:
            continue
        where = f"samples.{name} (row {i})"
        if column.dtype == OBJECT:
            checks.text(cell, where)
        elif column.dtype == FLOAT64:
            checks.number(cell, where)
        else:
            checks.integer(cell, where)
            if not -(2**63) <= cell < 2**63:
                raise checks.Bad(f"{where}: {cell} is out of the 64-bit range")


def open_run(path: str | Path) -> Run:
    """The run stored at ``path`` (read-only; a run still being written is read as it
    stands). `JournalError` (one line) if it is missing, not a gonio run file, or of a
    newer layout than this gonio reads."""
    path = Path(path)
    if not path.is_file():
        raise JournalError(f"{path}: no such run file")
    try:
        conn = readonly.connect(path)
    except sqlite3.Error as exc:
        raise JournalError(f"{path}: cannot open the run file: {exc}") from None
    try:
        return read_run(conn, path)
    finally:
        conn.close()
