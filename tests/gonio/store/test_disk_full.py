"""A disk that fills during a run, emulated by SQLite's page limit and by
a file-size limit (RLIMIT_FSIZE) on the acquiring process: the run stops cleanly (outcome
``journal``, exit 3 through the CLI), every committed sample intact, the file sound, and
the run resumes to completion, equal to an uninterrupted one."""

from __future__ import annotations

import resource
import signal
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gonio.acquire import observer
from gonio.cli import main
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.support.acquire import (
    PipeProgress,
    RunFiles,
    acquire_in_child,
    assert_same_samples,
    integrity,
    sample_values,
)


def pages(path: Path) -> int:
    conn = sqlite3.connect(path)
    try:
        conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        return int(conn.execute("PRAGMA page_count").fetchone()[0])
    finally:
        conn.close()


def assert_a_prefix_of(run: Run, expected: Run) -> None:
    """Every sample in ``run`` is the uninterrupted run's sample of that target."""
    got, want = sample_values(run), sample_values(expected)
    rows = np.searchsorted(expected.target, run.target)
    for name, value in want.items():
        if value.dtype == object:
            assert got[name].tolist() == value[rows].tolist(), name
        else:
            np.testing.assert_array_equal(got[name], value[rows], err_msg=name, strict=True)


def test_the_page_limit_stops_the_run_cleanly(
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
) -> None:
    files = run_files()
    expected = uninterrupted(files)
    full = tmp_path / "full.sqlite"
    files.start(full)
    empty = tmp_path / "empty.sqlite"
    files.start(empty, max_page_count=1)  # fails at once: the schema alone
    start, end = pages(empty), pages(full)
    assert end > start + 4
    path = tmp_path / "run.sqlite"
    outcome = files.start(path, max_page_count=(start + end) // 2)
    assert outcome.report.outcome == "journal"
    assert "cannot write the journal" in outcome.report.message
    assert integrity(path) == "ok"
    run = open_run(path)
    assert 0 < len(run) < len(expected)
    assert_a_prefix_of(run, expected)
    resumed = session.resume(path)  # room again
    assert resumed.report.outcome == "completed"
    assert integrity(path) == "ok"
    assert_same_samples(resumed.run, expected)


def test_a_file_size_limit_ends_gonio_acquire_with_exit_3(
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
    run_gonio: Callable[..., object],
) -> None:
    files = run_files()
    path = tmp_path / "run.sqlite"

    def limited(progress: PipeProgress) -> int:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes past the limit fail (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (96 * 1024, resource.RLIM_INFINITY))
        observer.for_stream = lambda quiet, stream=None: progress  # type: ignore[assignment]
        return main(files.cli(path))

    child = acquire_in_child(limited)
    assert child.last == "done 3", child.last
    assert integrity(path) == "ok"
    run = open_run(path)
    assert set(child.reported) <= set(run.target.tolist())
    assert 0 < len(run) < 60
    assert run.sessions[-1].outcome is None or run.sessions[-1].outcome == "journal"
    assert_a_prefix_of(run, uninterrupted(files))
    result = run_gonio("acquire", "--resume", str(path), "-q")
    assert result.returncode == 0, result.stderr  # type: ignore[attr-defined]
    assert_same_samples(open_run(path), uninterrupted(files))
