"""The run journal, written: one SQLite file per run (WAL mode), committed sample by
sample, that a crash never corrupts and a resumed run appends to.

The layout (schema version `SCHEMA_VERSION`) is documented in docs/reference/journal.md:

- ``meta`` (key → JSON text, or bytes for ``plan_file``): the plan, rig and scene
  texts and their hashes, the stored plan itself (`gonio.planner.stored`), the axes and
  coordinate names, the backend, the seed, the package versions, the host;
- ``sessions``: one row per process that wrote to the run (start, end, how it ended);
- ``samples``: one row per measured target (``target`` = its index in the plan), its
  columns defined in `gonio.store.schema`;
- ``sweeps`` (version 2): one row per sweep of a fly plan measured or abandoned, and
  beside it its raw streams, ``polls`` (stamped positions) and ``stream`` (stamped
  readings), so a run can be merged again with another timing model;
- ``events``: calibrations, darks, faults, retries, skips, pauses, resumes, health
  readings, the simulated backend's state snapshots.

Durability: ``durable=True`` (hardware) commits with ``PRAGMA synchronous=FULL``, so
every committed sample is on the disk (WAL fsync'ed) before the next move and survives
a power loss; ``durable=False`` (the simulated backend) commits each sample too, with
``synchronous=NORMAL``: a crash of the process loses nothing committed, a power loss
may lose the last commits (the run resumes from what is there). The writer holds an
exclusive `fcntl.flock` on the file for its whole life, so a second writer is refused
at once; readers (`gonio.store.open_run`) never take it.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import sqlite3
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from gonio.errors import GonioError
from gonio.store import checks, readonly
from gonio.store.schema import ADDED_IN_2, samples_ddl, samples_table

#: The layout version this gonio writes (and the newest it reads).
SCHEMA_VERSION = 2
#: ``PRAGMA application_id`` of a gonio run journal ("goni").
APPLICATION_ID = 0x676F6E69


class JournalError(GonioError):
    """The journal cannot be created, opened or written; the message is one line."""


class UnjournaledValue(GonioError):
    """A value the journal does not store (NaN, an infinity, a non-JSON value): a fault
    of the value's maker, so the run ends ``aborted`` (its session ended in the journal)
    rather than as a journal that cannot be written."""


_EVENTS_SQL = """CREATE TABLE events (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session INTEGER NOT NULL,
    kind TEXT NOT NULL,
    target INTEGER,
    t_s REAL NOT NULL,
    utc TEXT NOT NULL,
    data TEXT NOT NULL
)"""
_SWEEPS_SQL = (
    """CREATE TABLE sweeps (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session INTEGER NOT NULL,
    sweep INTEGER NOT NULL,
    outcome TEXT NOT NULL,
    started_s REAL NOT NULL,
    ended_s REAL NOT NULL,
    data TEXT NOT NULL
)""",
    """CREATE TABLE polls (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id),
    request_s REAL NOT NULL,
    reply_s REAL NOT NULL,
    positions TEXT NOT NULL
)""",
    """CREATE TABLE stream (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id),
    started_s REAL NOT NULL,
    ended_s REAL NOT NULL,
    value REAL NOT NULL,
    std REAL,
    saturated INTEGER NOT NULL,
    device_t_s REAL,
    received_s REAL
)""",
    "CREATE INDEX polls_sweep ON polls (sweep_id)",
    "CREATE INDEX stream_sweep ON stream (sweep_id)",
)
_SESSIONS_SQL = """CREATE TABLE sessions (
    id INTEGER PRIMARY KEY,
    started_utc TEXT NOT NULL,
    info TEXT NOT NULL,
    ended_utc TEXT,
    outcome TEXT
)"""


def dumps(value: Any) -> str:
    """JSON text of a journal value (no NaN nor infinity: a journal never stores one;
    `UnjournaledValue` naming where in ``value`` one is)."""
    try:
        return json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    except (ValueError, TypeError) as exc:
        where, bad = _unjournaled(value, "")
        shown = repr(bad)[:40]
        raise UnjournaledValue(
            f"cannot journal {where.lstrip('.') or 'a value'} = {shown}: the journal stores "
            f"finite numbers, text, lists and mappings only ({exc})"
        ) from None


def _unjournaled(value: Any, where: str) -> tuple[str, Any]:
    """(dotted path, value) of the first part of ``value`` JSON cannot hold exactly."""
    if isinstance(value, Mapping):
        for key, item in value.items():
            found = _unjournaled(item, f"{where}.{key}")
            if found[0]:
                return found
        return "", None
    if isinstance(value, list | tuple):
        for i, item in enumerate(value):
            found = _unjournaled(item, f"{where}.{i}")
            if found[0]:
                return found
        return "", None
    if value is None or isinstance(value, str | bool | int):
        return "", None
    if isinstance(value, float) and value - value == 0:
        return "", None
    return where or ".", value


def _lock(path: Path) -> int:
    """An open descriptor of ``path`` holding an exclusive flock (`JournalError` if
    another process holds it)."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_CLOEXEC)
    except OSError as exc:
        raise JournalError(f"{path}: cannot open the run file: {exc.strerror or exc}") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        raise JournalError(
            f"{path}: another gonio acquire is writing this run (the file is locked); "
            "wait for it to end or stop it first"
        ) from None
    return fd


def remove_run_file(path: Path) -> None:
    """Delete a run file and its WAL and shared-memory files."""
    for suffix in ("", "-wal", "-shm", "-journal"):
        Path(f"{path}{suffix}").unlink(missing_ok=True)


class Journal:
    """A run journal open for writing (see the module docstring). Use `create` for a new
    run or `reopen` to resume one; `close` (or ``with``) releases the file."""

    def __init__(self, conn: sqlite3.Connection, path: Path | None, lock_fd: int | None):
        self.conn = conn
        self.path = path
        self._lock_fd = lock_fd
        self.session = 0
        axes, coords = (self._meta_names(key) for key in ("axes", "coordinate_names"))
        self.columns = [c.name for c in samples_table(axes, coords)]
        names = ", ".join(f'"{c}"' for c in self.columns)
        marks = ", ".join("?" for _ in self.columns)
        self._insert = f"INSERT INTO samples ({names}) VALUES ({marks})"

    # -- opening ---------------------------------------------------------------------------
    @staticmethod
    def _connect(target: str, durable: bool, max_page_count: int | None) -> sqlite3.Connection:
        conn = sqlite3.connect(target, isolation_level=None, check_same_thread=False)
        conn.execute("PRAGMA journal_mode=WAL")
        _synchronous(conn, durable)
        if not durable:  # fewer, larger checkpoints: no stall every 1000 pages
            conn.execute("PRAGMA wal_autocheckpoint=16384")
        conn.execute("PRAGMA foreign_keys=ON")
        if max_page_count is not None:  # tests: a disk that fills up
            conn.execute(f"PRAGMA max_page_count={int(max_page_count)}")
        return conn

    @classmethod
    def create(
        cls,
        path: Path | None,
        meta: Mapping[str, Any],
        plan_file: bytes,
        *,
        durable: bool,
        overwrite: bool = False,
        max_page_count: int | None = None,
    ) -> Journal:
        """A new run file at ``path`` (None: in memory) with ``meta`` (JSON values; it
        must name ``axes`` and ``coordinate_names``) and the stored plan's bytes.

        An existing file is refused unless ``overwrite`` (and even then while another
        process writes it). The file is created and locked before anything is written
        to it, so nothing moves before the output is known to be usable.

        The run file appears complete or not at all: its schema and metadata are written
        to a hidden file beside it (``.NAME.creating-PID``), which is then linked to
        ``path`` (refused if ``path`` appeared meanwhile). A crash before that leaves only
        the hidden file; never a ``path`` that is neither a run nor free."""
        if path is None:
            conn = cls._connect(":memory:", durable, max_page_count)
            try:
                cls._write_schema(conn, meta, plan_file)
            except sqlite3.Error as exc:
                conn.close()
                raise JournalError(f"journal: cannot write the run file: {exc}") from None
            return cls(conn, None, None)
        if path.is_dir():
            raise JournalError(f"{path}: is a folder; expected a run file name")
        if path.exists() or path.is_symlink():
            if not overwrite:
                raise JournalError(
                    f"{path}: a run file already exists; give another name, continue it "
                    "with --resume, or replace it with --overwrite"
                )
            os.close(_lock(path))  # refuse to replace a run another process writes
            remove_run_file(path)
        creating = path.with_name(f".{path.name}.creating-{os.getpid()}")
        remove_run_file(creating)
        try:
            fd = os.open(creating, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o644)
        except OSError as exc:
            raise JournalError(
                f"{path}: cannot create the run file: {exc.strerror or exc}"
            ) from None
        os.close(fd)
        try:
            conn = cls._connect(str(creating), False, None)
            try:
                cls._write_schema(conn, meta, plan_file)
            finally:
                conn.close()  # the last connection: the WAL is checkpointed into the file
            os.link(creating, path)
        except (sqlite3.Error, OSError) as exc:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            raise JournalError(f"{path}: cannot write the run file: {why}") from None
        finally:
            remove_run_file(creating)
        lock = _lock(path)
        try:
            conn = cls._connect(str(path), durable, max_page_count)
        except sqlite3.Error as exc:
            os.close(lock)
            raise JournalError(f"{path}: cannot open the run file: {exc}") from None
        return cls(conn, path, lock)

    @staticmethod
    def _write_schema(conn: sqlite3.Connection, meta: Mapping[str, Any], plan: bytes) -> None:
        table = samples_table(meta["axes"], meta["coordinate_names"])
        conn.execute("BEGIN IMMEDIATE")
        conn.execute(f"PRAGMA application_id={APPLICATION_ID}")
        conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
        conn.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value NOT NULL)")
        conn.execute(_SESSIONS_SQL)
        conn.execute(samples_ddl(table))
        conn.execute(_EVENTS_SQL)
        conn.execute("CREATE INDEX events_kind ON events (kind)")
        for sql in _SWEEPS_SQL:
            conn.execute(sql)
        rows: list[tuple[str, str | bytes]] = [(k, dumps(v)) for k, v in meta.items()]
        rows += [("schema_version", dumps(SCHEMA_VERSION)), ("plan_file", plan)]
        conn.executemany("INSERT INTO meta VALUES (?, ?)", rows)
        conn.execute("COMMIT")

    @classmethod
    def reopen(cls, path: Path, *, durable: bool, max_page_count: int | None = None) -> Journal:
        """An existing run file, to append to (`JournalError` if it is missing, not a
        gonio run, of a newer layout, or being written by another process); an older
        layout is brought to this one by `upgrade`, once the caller's checks passed."""
        if not path.is_file():
            raise JournalError(f"{path}: no such run file")
        lock = _lock(path)
        try:
            # Read-only first: a file that is not a gonio run (another program's database,
            # zero bytes) is refused before anything is written to it (the WAL mode) or
            # made beside it (the lock is ours: nobody else writes it).
            probe = readonly.connect(path, still=readonly.is_still(path, writing=False))
            try:
                check_version(probe, path)
            finally:
                probe.close()
            conn = cls._connect(str(path), durable, max_page_count)
            check_version(conn, path)
            return cls(conn, path, lock)
        except (sqlite3.Error, GonioError) as exc:
            os.close(lock)
            if isinstance(exc, GonioError):
                raise
            raise JournalError(f"{path}: not a usable run file: {exc}") from None

    # -- writing ---------------------------------------------------------------------------
    def upgrade(self) -> None:
        """Bring a reopened run file of an older layout to this one (one transaction);
        nothing when it is current. Called before the first write, so a resume refused
        by its checks leaves the file as it was."""
        try:
            _upgrade(self.conn)
        except sqlite3.Error as exc:
            raise JournalError(
                f"{self.path}: cannot bring the run file up to date: {exc}"
            ) from None

    def make_durable(self, durable: bool) -> None:
        """Commit with ``synchronous=FULL`` (``durable``: a power loss loses nothing
        committed) or ``NORMAL`` from now on; a resumed run learns which from its backend
        after the file is opened."""
        _synchronous(self.conn, durable)

    def anything_recorded(self) -> bool:
        """Whether the run holds a sample or an event other than its start."""
        samples = self.conn.execute("SELECT COUNT(*) FROM samples").fetchone()[0]
        events = self.conn.execute(
            "SELECT COUNT(*) FROM events WHERE kind NOT IN ('start')"
        ).fetchone()[0]
        return bool(samples or events)

    def _meta_text(self, key: str) -> str:
        row = self.conn.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        if row is None:
            raise JournalError(f"{self.path}: meta.{key}: missing")
        return str(row[0])

    def _meta_names(self, key: str) -> list[str]:
        """A list of names in ``meta`` (`JournalError`, one line, if it is not one)."""
        try:
            return checks.names(checks.json_value(self._meta_text(key), f"meta.{key}"), key)
        except checks.Bad as exc:
            raise JournalError(f"{self.path}: not a usable run file: {exc}") from None

    def _write(self, sql: str, args: Sequence[Any]) -> None:
        try:
            self.conn.execute(sql, args)
        except sqlite3.Error as exc:
            raise JournalError(
                f"{self.path or 'journal'}: cannot write the journal ({exc}); every sample "
                "committed so far is kept and the run can be resumed"
            ) from None

    def start_session(self, utc: str, info: Mapping[str, Any]) -> int:
        """Record a new writing session; returns its number (1, 2, …)."""
        row = self.conn.execute("SELECT COALESCE(MAX(id), 0) FROM sessions").fetchone()
        self.session = int(row[0]) + 1
        self._write(
            "INSERT INTO sessions (id, started_utc, info) VALUES (?, ?, ?)",
            (self.session, utc, dumps(dict(info))),
        )
        return self.session

    def end_session(self, utc: str, outcome: str) -> None:
        self._write(
            "UPDATE sessions SET ended_utc = ?, outcome = ? WHERE id = ?",
            (utc, outcome, self.session),
        )

    def replace_plan(self, plan_file: bytes) -> None:
        """Store a new plan in place of the run's (an adaptive plan's second pass appended
        to its survey: the targets measured keep their indices)."""
        self._write("UPDATE meta SET value = ? WHERE key = 'plan_file'", (plan_file,))

    def sample(self, row: Mapping[str, Any]) -> None:
        """Commit one measured target (every column of `gonio.store.schema.samples_table`
        but ``session``)."""
        values = [self.session if c == "session" else row[c] for c in self.columns]
        self._write(self._insert, values)

    def event(
        self,
        kind: str,
        t_s: float,
        utc: str,
        data: Mapping[str, Any] | None = None,
        target: int | None = None,
    ) -> None:
        """Commit one event (``data``: JSON values)."""
        self._write(
            "INSERT INTO events (session, kind, target, t_s, utc, data) VALUES (?, ?, ?, ?, ?, ?)",
            (self.session, kind, target, float(t_s), utc, dumps(dict(data or {}))),
        )

    @contextlib.contextmanager
    def transaction(self) -> Iterator[None]:
        """Everything written inside commits at once at the end (rolled back if it
        raises): a crash leaves all of it or none."""
        self._write("BEGIN IMMEDIATE", ())
        try:
            yield
        except BaseException:
            with contextlib.suppress(sqlite3.Error):
                self.conn.execute("ROLLBACK")
            raise
        self._write("COMMIT", ())

    def sweep(
        self,
        sweep: int,
        outcome: str,
        started_s: float,
        ended_s: float,
        data: Mapping[str, Any],
        polls: Sequence[tuple[float, float, Sequence[float]]],
        stream: Sequence[tuple[float, float, float, float | None, int, float | None, float | None]],
    ) -> None:
        """Journal one sweep of a fly plan (``outcome`` ``measured`` or ``abandoned``)
        and its raw streams: ``polls`` (request s, reply s, positions rad in the axes'
        order) and ``stream`` (started s, ended s, value, std, saturated, device_t_s,
        received_s); times in run time."""
        self._write(
            "INSERT INTO sweeps (session, sweep, outcome, started_s, ended_s, data) "
            "VALUES (?, ?, ?, ?, ?, ?)",
            (self.session, sweep, outcome, started_s, ended_s, dumps(dict(data))),
        )
        row = self.conn.execute("SELECT last_insert_rowid()").fetchone()[0]
        try:
            self.conn.executemany(
                "INSERT INTO polls VALUES (?, ?, ?, ?)",
                [(row, a, b, dumps(list(p))) for a, b, p in polls],
            )
            self.conn.executemany(
                "INSERT INTO stream VALUES (?, ?, ?, ?, ?, ?, ?, ?)", [(row, *r) for r in stream]
            )
        except sqlite3.Error as exc:
            raise JournalError(
                f"{self.path or 'journal'}: cannot write the journal ({exc}); every sweep "
                "committed so far is kept and the run can be resumed"
            ) from None

    # -- closing ---------------------------------------------------------------------------
    def close(self) -> None:
        """Close the database and release the lock (idempotent)."""
        if self.conn is not None:
            with contextlib.suppress(sqlite3.Error):
                self.conn.close()
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _synchronous(conn: sqlite3.Connection, durable: bool) -> None:
    conn.execute(f"PRAGMA synchronous={'FULL' if durable else 'NORMAL'}")


def check_version(conn: sqlite3.Connection, path: Path) -> None:
    """`JournalError` unless ``conn`` is a gonio run journal this gonio can read."""
    app = conn.execute("PRAGMA application_id").fetchone()[0]
    if app != APPLICATION_ID:
        raise JournalError(f"{path}: not a gonio run file (application_id {app:#x})")
    version = conn.execute("PRAGMA user_version").fetchone()[0]
    if version > SCHEMA_VERSION:
        raise JournalError(
            f"{path}: run file schema version {version}; this gonio reads versions up to "
            f"{SCHEMA_VERSION} (update gonio to read it)"
        )


def _upgrade(conn: sqlite3.Connection) -> None:
    """Bring a version-1 run file being resumed to version 2 in one transaction: the
    samples' fly columns (NULL for what was measured) and the sweep tables."""
    if conn.execute("PRAGMA user_version").fetchone()[0] >= SCHEMA_VERSION:
        return
    conn.execute("BEGIN IMMEDIATE")
    for name in ADDED_IN_2:
        conn.execute(f'ALTER TABLE samples ADD COLUMN "{name}" REAL')
    for sql in _SWEEPS_SQL:
        conn.execute(sql)
    conn.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (dumps(2),))
    conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
    conn.execute("COMMIT")
