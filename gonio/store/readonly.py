"""Opening a run file for reading so that the folder is left as it was found.

Every run file is in WAL mode. SQLite reads such a file through its ``-wal`` and
``-shm`` files and creates them when they are missing, even for a read-only connection
(``mode=ro`` keeps the connection from writing the database, not SQLite from making
those files beside it); the last connection to close deletes them after a checkpoint,
which a read-only connection cannot do, so they would stay behind. Hence:

- a run nobody writes (`is_still`: no ``-wal`` beside it, so the writer's last close
  checkpointed the file and removed it, and no ``gonio acquire`` holds the writer's
  lock) is opened ``immutable=1``: read as the file stands, no lock taken, nothing made;
- a run being written (its ``-wal`` is there, or its writer holds the lock) is opened
  ``mode=ro`` through the writer's WAL and sees each commit; the side files are the
  writer's (and stay if the writer ends while a reader still has the file open: only
  the last connection, if it can write, removes them).

A reader that lives on (`gonio.store.follow.RunFollower`) asks `is_still` again at each
read and opens the file ``mode=ro`` once a writer appears.
"""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path

#: Seconds a reader waits for a lock another process holds on the file (a writer that
#: took it whole: ``PRAGMA locking_mode=EXCLUSIVE``, or a checkpoint) before giving up
#: with one line; gonio's own writer never blocks readers (WAL mode).
BUSY_TIMEOUT_S = 5.0


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


def is_still(path: Path, *, writing: bool | None = None) -> bool:
    """Whether nobody writes the run file at ``path``: no ``-wal`` file beside it and no
    writer's lock on it (``writing``: whether a writer holds it, when the caller knows;
    the caller that holds the lock itself passes False)."""
    if writing is None:
        writing = writer_holds(path)
    return not writing and not os.path.lexists(f"{path}-wal")


def connect(path: Path, *, still: bool | None = None, threads: bool = False) -> sqlite3.Connection:
    """A read-only connection to the run file ``path`` (module docstring): immutable if
    ``still`` (default: `is_still`), else through the writer's WAL. ``threads``: usable
    from other threads than this one. `sqlite3.Error` if it cannot be opened."""
    if still is None:
        still = is_still(path)
    uri = f"{path.resolve().as_uri()}?mode=ro" + ("&immutable=1" if still else "")
    return sqlite3.connect(
        uri, uri=True, isolation_level=None, check_same_thread=not threads, timeout=BUSY_TIMEOUT_S
    )


__all__ = ["BUSY_TIMEOUT_S", "connect", "is_still", "writer_holds"]
