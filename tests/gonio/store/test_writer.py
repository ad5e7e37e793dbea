"""The run journal's file: one writer at a time, a version this gonio can read, a file
that is a gonio run."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from gonio.store import Journal, JournalError, open_run
from tests.support.acquire import acquire, plan_file, scene_file


@pytest.fixture
def run_path(tmp_path: Path) -> Path:
    out = tmp_path / "run.sqlite"
    acquire(plan_file(tmp_path, target=5), scene_file(tmp_path), out)
    return out


def test_a_second_writer_is_refused_while_the_first_holds_the_run(run_path: Path) -> None:
    with Journal.reopen(run_path, durable=False):
        with pytest.raises(JournalError, match="another gonio acquire is writing this run"):
            Journal.reopen(run_path, durable=False)
        assert len(open_run(run_path)) == 5  # readers are never locked out
    Journal.reopen(run_path, durable=False).close()  # released on close


def test_a_newer_layout_is_refused_in_one_line(run_path: Path) -> None:
    with sqlite3.connect(run_path) as conn:
        conn.execute("PRAGMA user_version=99")
    with pytest.raises(JournalError) as info:
        open_run(run_path)
    assert str(info.value) == (
        f"{run_path}: run file schema version 99; this gonio reads versions up to 2 "
        "(update gonio to read it)"
    )
    with pytest.raises(JournalError, match="schema version 99"):
        Journal.reopen(run_path, durable=False)


@pytest.mark.parametrize("content", [b"", b"not a database at all" * 100])
def test_a_file_that_is_not_a_run_is_refused(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "x.sqlite"
    path.write_bytes(content)
    with pytest.raises(JournalError) as info:
        open_run(path)
    assert str(info.value).startswith(f"{path}: not a")
    assert "\n" not in str(info.value)


def test_other_sqlite_files_are_not_runs(tmp_path: Path) -> None:
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as conn:
        conn.execute("CREATE TABLE t (x)")
    with pytest.raises(JournalError, match=r"not a gonio run file \(application_id 0x0\)"):
        open_run(path)


def test_a_missing_run_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(JournalError, match="no such run file"):
        open_run(tmp_path / "nope.sqlite")


def test_the_file_is_wal_and_passes_the_integrity_check(run_path: Path) -> None:
    with sqlite3.connect(run_path) as conn:
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
