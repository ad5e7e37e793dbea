"""The run file read with plain SQL, not through `gonio.store`: the check does not
trust the reader it checks."""

from __future__ import annotations

import json
import sqlite3
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml


def connect(path: Path) -> sqlite3.Connection:
    """An autocommit connection to the run file ``path`` (waits up to 30 s on a lock)."""
    return sqlite3.connect(path, timeout=30.0, isolation_level=None)


def progress(conn: sqlite3.Connection) -> int:
    """The highest target committed (targets are measured in index order), −1 if none."""
    try:
        row = conn.execute("SELECT MAX(target) FROM samples").fetchone()
    except sqlite3.Error:
        return -1
    return -1 if row is None or row[0] is None else int(row[0])


def integrity(path: Path) -> str:
    """``PRAGMA integrity_check`` of ``path`` ('ok' when sound)."""
    conn = connect(path)
    try:
        return "\n".join(str(r[0]) for r in conn.execute("PRAGMA integrity_check"))
    finally:
        conn.close()


def finished(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(targets measured, targets skipped) in ``path``, each sorted."""
    conn = connect(path)
    try:
        measured = np.array([r[0] for r in conn.execute("SELECT target FROM samples")], np.int64)
        skipped = [
            r[0]
            for r in conn.execute("SELECT target FROM events WHERE kind = 'skip'")
            if r[0] is not None
        ]
    finally:
        conn.close()
    return np.sort(measured), np.sort(np.array(skipped, dtype=np.int64))


@dataclass(frozen=True)
class Event:
    id: int
    session: int
    kind: str
    target: int | None
    t_s: float
    data: dict[str, Any]


@dataclass
class Journal:
    """What a run file says, read with plain SQL."""

    events: list[Event]
    sessions: list[tuple[int, str | None, int]]  # (id, outcome, pid)
    samples: dict[str, np.ndarray]  # column → values, ordered by target
    targets: int  # the plan's

    @classmethod
    def read(cls, path: Path) -> Journal:
        conn = connect(path)
        try:
            events = [
                Event(
                    int(i), int(s), str(k), None if t is None else int(t), float(ts), json.loads(d)
                )
                for i, s, k, t, ts, d in conn.execute(
                    "SELECT id, session, kind, target, t_s, data FROM events ORDER BY id"
                )
            ]
            sessions = [
                (int(i), o, int(json.loads(info).get("pid", 0)))
                for i, o, info in conn.execute("SELECT id, outcome, info FROM sessions")
            ]
            cursor = conn.execute("SELECT * FROM samples ORDER BY target")
            names = [c[0] for c in cursor.description]
            rows = cursor.fetchall()
            plan = json.loads(conn.execute("SELECT value FROM meta WHERE key = 'plan_text'")
                              .fetchone()[0])  # fmt: skip
        finally:
            conn.close()
        columns = {n: np.array([r[k] for r in rows], dtype=object) for k, n in enumerate(names)}
        targets = int(yaml.safe_load(plan)["sampling"]["target"])
        return cls(events, sessions, columns, targets)

    def of_kind(self, kind: str) -> list[Event]:
        return [e for e in self.events if e.kind == kind]
