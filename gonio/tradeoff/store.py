"""A sweep's output folder: finished combinations kept one JSON line each in
``results.jsonl``, appended and flushed to the disk as each finishes, so a sweep killed
at any moment loses only the combinations in flight and a sweep run again into the same
folder skips the finished ones; ``results.csv`` is rendered from those lines.

A line cut short by the kill (the last one, without its newline) is dropped when the
folder is opened again. The folder is locked (``.lock``, `fcntl.flock`) while a sweep
writes it: two sweeps never append to one file. Floats are written by ``repr`` (JSON),
so a row reads back bit for bit.
"""

from __future__ import annotations

import contextlib
import csv
import fcntl
import io
import json
import os
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from gonio.config import ConfigError
from gonio.output import reserve_output

RESULTS_JSONL = "results.jsonl"
RESULTS_CSV = "results.csv"


class Store:
    """The finished rows of an output folder (`open_store`); `append` one more."""

    def __init__(self, folder: Path, fd: int, rows: dict[str, dict[str, Any]]) -> None:
        self.folder = folder
        self._fd = fd
        self.rows = rows  # id → row, in the order they finished

    def append(self, row: dict[str, Any]) -> None:
        """Add a finished row: one line written and flushed to the disk before return."""
        line = json.dumps(row, ensure_ascii=False, allow_nan=False) + "\n"
        try:
            os.write(self._fd, line.encode("utf-8"))
            os.fsync(self._fd)
        except OSError as exc:
            raise ConfigError(
                f"-o {self.folder}: cannot write {RESULTS_JSONL}: {exc.strerror or exc}; the "
                "rows written so far are kept (run the sweep again to go on)"
            ) from None
        self.rows[row["id"]] = row


@contextlib.contextmanager
def open_store(folder: Path) -> Iterator[Store]:
    """The output ``folder`` (created if missing; its parent must exist), locked and
    with its finished rows read; `ConfigError` (one line) if it cannot be used."""
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"-o {folder}: is a file; expected an output folder")
    try:
        folder.mkdir(exist_ok=True)
        lock = os.open(folder / ".lock", os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise ConfigError(f"-o {folder}: cannot use it: {exc.strerror or exc}") from None
    try:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(f"-o {folder}: another sweep is writing this folder") from None
        path = folder / RESULTS_JSONL
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o666)
        try:
            rows = _read(path, fd)
            yield Store(folder, fd, rows)
        finally:
            os.close(fd)
    finally:
        os.close(lock)


def _read(path: Path, fd: int) -> dict[str, dict[str, Any]]:
    """The rows of ``results.jsonl``; a last line cut short is cut off the file."""
    with open(path, "rb") as stream:
        data = stream.read()
    complete = data.rfind(b"\n") + 1
    if complete < len(data):  # a torn last line: the sweep was killed while writing it
        os.ftruncate(fd, complete)
    rows: dict[str, dict[str, Any]] = {}
    for n, line in enumerate(data[:complete].splitlines(), 1):
        try:
            row = json.loads(line)
        except (ValueError, UnicodeDecodeError):
            raise ConfigError(
                f"{path}:{n}: not a results row; expected one JSON object per line"
            ) from None
        if not isinstance(row, dict) or not isinstance(row.get("id"), str):
            raise ConfigError(f"{path}:{n}: not a results row; expected an object with an id")
        rows[row["id"]] = row
    return rows


def csv_text(rows: Iterable[dict[str, Any]], columns: Sequence[str]) -> str:
    """``rows`` as CSV with a header of ``columns`` (a missing value or None: empty;
    floats as ``repr``, which reads back exactly)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow(["" if row.get(c) is None else row[c] for c in columns])
    return out.getvalue()


def write_csv(folder: Path, rows: Iterable[dict[str, Any]], columns: Sequence[str]) -> Path:
    """``results.csv`` in ``folder``, written atomically (`gonio.output`)."""
    path = folder / RESULTS_CSV
    with reserve_output(path, "-o") as pending:
        pending.write_bytes(csv_text(rows, columns).encode("utf-8"))
    return path
