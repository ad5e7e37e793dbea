"""Following a run file as it grows: `RunFollower` reads, at each `RunFollower.refresh`,
only what was committed since the last one (the samples' columns a live view needs, by
target: the rowid; the new events; the sessions), each read in one read transaction of
a read-only connection, so it sees a consistent snapshot while ``gonio acquire`` writes
(SQLite's WAL). Every row it hands on passed the checks `open_run` applies
(`gonio.store.checks` through `gonio.store.read`): a damaged or edited file is
`JournalError`, one line naming the file and the field, at the refresh that meets it.

A large run (over `FULL_LIMIT` samples) is read by a share of its targets plus every
sample committed since, and its stored plan (over `LAZY_PLAN_BYTES`) by its header at
once and its targets in another process (`gonio.store.plan_view`): a run of a million
samples opens in seconds, not minutes (docs/results/live.md). `writer_holds` tells
whether a ``gonio acquire`` holds the file's writer lock (nothing is locked or opened for
writing to find out). A run nobody writes is read as it stands, with nothing made beside
it, until a writer appears (`gonio.store.readonly`).
"""

from __future__ import annotations

import math
import multiprocessing
import os
import sqlite3
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from gonio.planner import parse_plan
from gonio.store import checks
from gonio.store.journal import JournalError, check_version
from gonio.store.plan_view import PlanArrays, PlanInfo, parse_in_background
from gonio.store.read import (
    Event,
    Session,
    check_plan,
    check_samples,
    check_targets,
    decode_meta,
    event_of,
    refusing,
    sample_columns,
    session_of,
)
from gonio.store.readonly import connect, is_still, writer_holds
from gonio.store.schema import samples_table

#: The sample columns a follower reads (besides ``utc``, when the table has it).
COLUMNS = (
    "target", "counts", "counts_std", "n", "exposure_s", "started_s", "ended_s",
    "saturated", "wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z",
)  # fmt: skip
#: Samples whose wall time (UTC) the rate is measured over.
RATE_WINDOW = 200
#: A run of at most this many samples is read whole; a larger one about `KEPT` of them
#: (every k-th target) and every sample committed since.
FULL_LIMIT = 200_000
KEPT = 50_000
#: A stored plan larger than this (bytes; about 30 000 targets) is parsed in the
#: background; its header is read at once.
LAZY_PLAN_BYTES = 8_000_000
_HEAD_BYTES = 4_000_000


def _epoch(utc: Any) -> float:
    try:
        return datetime.fromisoformat(utc).timestamp()
    except (TypeError, ValueError):
        return math.nan


def _identity(path: Path) -> tuple[int, int] | None:
    """The file ``path`` names (device, inode), None if none."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


@dataclass
class RunFollower:
    """A run file followed as it grows (see the module docstring). `JournalError` (one
    line) if ``path`` is not a readable run file, at once or at the refresh that finds
    it damaged.

    ``samples``: the samples' columns in `COLUMNS`, in commit order: every sample of a
    run of at most `FULL_LIMIT` when first read, else about `KEPT` of those already
    there (every k-th target) and every one committed since. ``measured``: how many
    the run holds. The stored plan itself (`plan`) is parsed once, in the background
    when it is large (its header, `info`, is read at once). ``version`` changes
    whenever something new is read (or the writer came or went)."""

    path: Path
    version: int = field(init=False, default=0)
    meta: Mapping[str, Any] = field(init=False)
    info: PlanInfo = field(init=False)
    samples: dict[str, np.ndarray] = field(init=False)
    measured: int = field(init=False, default=0)
    skipped: int = field(init=False, default=0)
    events: list[Event] = field(init=False, default_factory=list)
    sessions: tuple[Session, ...] = field(init=False, default=())
    _conn: sqlite3.Connection = field(init=False, repr=False)
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
    _broken: str | None = field(init=False, default=None)  # why the plan cannot be read
    _identity: tuple[int, int] | None = field(init=False, default=None)
    _still: bool = field(init=False, default=False)  # opened immutable: nobody wrote it

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        if not self.path.is_file():
            raise JournalError(f"{self.path}: no such run file")
        self._identity = _identity(self.path)
        self._connect(is_still(self.path))
        try:
            with refusing(self.path):
                check_version(self._conn, self.path)
            self.samples = {}
            self.refresh()
        except BaseException:
            self._conn.close()
            raise

    def _connect(self, still: bool) -> None:
        try:
            self._conn = connect(self.path, still=still, threads=True)
        except sqlite3.Error as exc:
            raise JournalError(f"{self.path}: cannot open the run file: {exc}") from None
        self._still = still

    def close(self) -> None:
        self._conn.close()

    def replaced(self) -> bool:
        """Whether the path now names another file (a run started again over it with
        ``--overwrite``, or removed): this follower reads the file it opened."""
        return _identity(self.path) != self._identity

    def refresh(self) -> bool:
        """Read what was committed since the last refresh; whether anything was (or the
        writer came or went). `JournalError` if what was committed is not the writer's."""
        if self._broken is not None:
            raise JournalError(self._broken)
        if self._load_next:
            self._start_loader()
        self._poll_loader()
        writing = writer_holds(self.path)
        if self._still and not is_still(self.path, writing=writing):  # a writer came
            self._conn.close()
            self._connect(still=False)
            self._data_version = -1
        with refusing(self.path):
            changed = self._read()
        if changed or writing != self._writing:
            self._writing = writing
            self.version += 1
            return True
        return False

    @property
    def writing(self) -> bool:
        """A ``gonio acquire`` holds the run file (as of the last refresh)."""
        return self._writing

    # -- reading -------------------------------------------------------------------------
    def _read(self) -> bool:
        conn = self._conn
        data_version = int(conn.execute("PRAGMA data_version").fetchone()[0])
        if data_version == self._data_version:
            return False
        conn.execute("BEGIN")
        try:
            row = conn.execute(
                "SELECT typeof(value), length(value) FROM meta WHERE key = 'plan_file'"
            ).fetchone()
            if row is None:
                raise checks.Bad("meta.plan_file: missing")
            if row[0] != "blob":
                raise checks.Bad(f"meta.plan_file: expected the stored plan's bytes, got {row[0]}")
            plan_size = int(row[1])
            if plan_size != self._plan_size:  # the first read, or an adaptive second pass
                self._read_meta(conn, plan_size)
            names = [r[1] for r in conn.execute("PRAGMA table_info(samples)")]
            table = samples_table(self.meta["axes"], self.meta["coordinate_names"])
            sample_columns(names, [], table)  # a column missing
            wanted = [c for c in (*COLUMNS, "utc") if c in names]
            quoted = ", ".join(f'"{c}"' for c in wanted)
            first = not self.samples
            measured, top, recent = self.measured, self._top, None
            if first:  # one scan of the table: later reads seek by target (the rowid)
                count = conn.execute("SELECT count(*) FROM samples").fetchone()[0]
                most = conn.execute("SELECT max(target) FROM samples").fetchone()[0]  # rowid
                measured, top = int(count), -1 if most is None else checks.integer(most, "target")
            if first and measured > FULL_LIMIT:
                stride = -(-(top + 1) // KEPT)
                rows = conn.execute(
                    "WITH RECURSIVE k(t) AS (SELECT 0 UNION ALL SELECT t + ? FROM k WHERE t + ? "
                    f"<= ?) SELECT {quoted} FROM samples JOIN k ON target = k.t ORDER BY target",
                    (stride, stride, top),
                ).fetchall()
                newest = conn.execute(
                    "SELECT ended_s, utc FROM samples ORDER BY target DESC LIMIT ?",
                    (RATE_WINDOW,),
                ).fetchall()
                recent = sorted((checks.number(t, "samples.ended_s"), _epoch(u)) for t, u in newest)
            elif first:
                rows = conn.execute(f"SELECT {quoted} FROM samples ORDER BY ended_s").fetchall()
            else:
                # What was committed since: targets beyond the last one read (a plan is
                # measured in its order), and skipped targets measured again since.
                rows = conn.execute(
                    f"SELECT {quoted} FROM samples WHERE target > ? ORDER BY target", (top,)
                ).fetchall()
                rows += self._retried(conn, quoted)
                measured += len(rows)
            events = conn.execute(
                "SELECT id, session, kind, target, t_s, utc, data FROM events WHERE id > ? "
                "ORDER BY id",
                (self._last_event,),
            ).fetchall()
            sessions = conn.execute(
                "SELECT id, started_utc, info, ended_utc, outcome FROM sessions ORDER BY id"
            ).fetchall()
            columns = sample_columns(wanted, rows, [c for c in table if c.name in wanted])
            check_targets(columns["target"], self.info.targets)
            check_samples(columns)
            new_events = [event_of(row) for row in events]
            self.sessions = tuple(session_of(row) for row in sessions)
            self.events.extend(new_events)
            if new_events:
                self._last_event = new_events[-1].id
            retried = self._skipped(conn)
            self._data_version = data_version
        finally:
            conn.execute("COMMIT")
        self.measured = measured
        if len(columns["target"]):
            top = max(top, int(columns["target"].max()))
        self._top = top
        if first:
            self._retried_targets = retried
        if recent is not None:
            self._recent = recent
        skips = {e.target for e in self.events if e.kind == "skip" and e.target is not None}
        self.skipped = len(skips) - len(retried)
        self._add_samples(columns, track=not (first and measured > FULL_LIMIT))
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
        self._retried_targets.update(r[0] for r in rows if type(r[0]) is int)
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
        rows = conn.execute("SELECT key, value FROM meta WHERE key != 'plan_file'").fetchall()
        meta = decode_meta(rows)
        rowid = conn.execute("SELECT rowid FROM meta WHERE key = 'plan_file'").fetchone()[0]
        with conn.blobopen("meta", "value", rowid, readonly=True) as blob:  # its start only
            head = blob.read(_HEAD_BYTES)
        plan = None
        if plan_size <= LAZY_PLAN_BYTES:  # parsed whole: its own checks first
            raw = conn.execute("SELECT value FROM meta WHERE key = 'plan_file'").fetchone()[0]
            plan = parse_plan(bytes(raw), f"{self.path}#plan_file")
            check_plan(meta, plan)
            targets = np.array([r[0] for r in conn.execute("SELECT target FROM samples")])
            if targets.size and targets.dtype != np.int64:
                raise checks.Bad("samples.target: expected whole numbers")
            check_targets(targets, len(plan))
        rig_where = f"{self.path}#rig_text"
        aligned = meta.get("alignment_text")
        info = PlanInfo.of(
            bytes(head),
            str(meta.get("rig_text", "")),
            rig_where,
            None if aligned is None else str(aligned),
        )
        self.meta, self.info, self._plan_size = MappingProxyType(meta), info, plan_size
        with self._lock:
            self._plan, self._done = None, None
        if plan is not None:
            self._install(PlanArrays.of(plan), targets.astype(np.int64))
        else:  # another process, from the next refresh on (not competing with this one)
            self._load_next = True

    def _start_loader(self) -> None:
        """Parse the plan in another process (parsing holds an interpreter for seconds)."""
        self._load_next = False
        context = multiprocessing.get_context("spawn")
        mine, theirs = context.Pipe(duplex=False)
        process = context.Process(target=parse_in_background, args=(self.path, theirs), daemon=True)
        process.start()
        theirs.close()
        self._loader = (process, mine)

    def _install(self, arrays: PlanArrays, targets: np.ndarray) -> None:
        done = np.zeros(len(arrays.per_target_s), dtype=np.bool_)
        done[targets] = True
        with self._lock:
            if self._done is not None:  # marked meanwhile by new samples
                done |= self._done[: len(done)]
            self._plan, self._done = arrays, done

    def _poll_loader(self) -> None:
        """Install what the background process parsed, once it sent it (`JournalError`
        if the plan cannot be read)."""
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
        if isinstance(result, str):
            self._broken = result
            raise JournalError(result)
        if result is None:
            return  # the process died: the views go on with the plan's header
        self._install(*result)
        self._data_version = -1

    def _add_samples(self, columns: Mapping[str, np.ndarray], track: bool) -> None:
        names = [n for n in columns if n != "utc"]
        if not self.samples:  # the first read (its columns' dtypes, even when empty)
            samples = {n: columns[n] for n in names}
        elif len(columns["target"]):
            samples = {n: np.concatenate([self.samples[n], columns[n]]) for n in names}
        else:
            return
        with self._lock:
            if self._done is not None:
                self._done[columns["target"]] = True
        self.samples = samples
        if track and "utc" in columns:
            ended, utc = columns["ended_s"][-RATE_WINDOW:], columns["utc"][-RATE_WINDOW:]
            self._recent.extend(zip(ended.tolist(), map(_epoch, utc), strict=True))
            self._recent = self._recent[-RATE_WINDOW:]

    # -- what is derived ---------------------------------------------------------------
    @property
    def plan(self) -> PlanArrays | None:
        """What a live view uses of the stored plan's targets, once parsed (None while a
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
        """The events of these kinds, in order."""
        return [e for e in self.events if e.kind in kinds]

    @property
    def complete(self) -> bool:
        """The last session ended the run (for an adaptive plan, its second pass too)."""
        done = bool(self.sessions) and self.sessions[-1].outcome == "completed"
        return done and not self.info.survey

    def rate_per_s(self) -> float | None:
        """Samples per second of wall time over the last samples, the time the run was
        held in between not counted (`held_s`; None: too few)."""
        recent = [u for _, u in self._recent if math.isfinite(u)]
        if len(recent) < 3 or recent[-1] <= recent[0]:
            return None
        active = recent[-1] - recent[0] - self.held_s(recent[0], recent[-1])
        return (len(recent) - 1) / active if active > 0 else None

    def held_s(self, start: float, end: float) -> float:
        """Wall time (s) between the epochs ``start`` and ``end`` during which the run was
        held: from a ``pause`` or ``stop`` event to the next ``resume`` or ``start``, and
        from a session's end to the next session's start."""
        spans: list[tuple[float, float]] = []
        opened: float | None = None
        for e in self.events:
            if e.kind in ("pause", "stop") and opened is None:
                opened = _epoch(e.utc)
            elif e.kind in ("resume", "start") and opened is not None:
                spans.append((opened, _epoch(e.utc)))
                opened = None
        if opened is not None:
            spans.append((opened, math.inf))
        for before, after in zip(self.sessions, self.sessions[1:], strict=False):
            if before.ended_utc is not None:
                spans.append((_epoch(before.ended_utc), _epoch(after.started_utc)))
        held, reached = 0.0, start
        for a, b in sorted(x for x in spans if math.isfinite(x[0]) and not math.isnan(x[1])):
            a, b = max(a, reached), min(b, end)
            if b > a:
                held += b - a
                reached = b
        return held


__all__: Sequence[str] = (
    "COLUMNS",
    "FULL_LIMIT",
    "KEPT",
    "LAZY_PLAN_BYTES",
    "RunFollower",
    "writer_holds",
)
