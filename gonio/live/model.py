"""The read model of a run shared by ``gonio serve`` and ``gonio watch``: a run file
followed as it grows (`LiveRun`; what is shown of it: `gonio.live.views`).

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
