"""kill -9 of the acquiring process at random moments: after every kill
the run file passes `PRAGMA integrity_check`, holds every sample the process reported
committed (at most the sample in flight is lost), and resumes; the completed run equals
an uninterrupted one bit for bit.

Each kill is of a real process: the test forks a child that runs `session.start` or
`session.resume` on the run file (everything imported once, in the test) and SIGKILLs it
a seeded random time after a seeded number of targets; a few kills are of `python -m
gonio acquire` itself, to cover the console entry point."""

from __future__ import annotations

import random
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.store.journal import remove_run_file
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.support.acquire import (
    PipeProgress,
    RunFiles,
    acquire_in_child,
    assert_same_samples,
    integrity,
)

#: Seeds of the kill schedules, and the kills each makes at least (≥ 100 in all).
KILL_SEEDS = (0, 1, 2, 3)
KILLS_PER_SEED = 26
#: Faults on the way, so kills also land after a retry (a mid-sample snapshot), a
#: saturated reading measured again, and in a health pause (a motor hot from the move
#: into target 12 until 30 s later; health is checked every 10 targets).
FAULTS = [
    {"kind": "comm_error", "at": [7, 33]},
    {"kind": "detector_error", "at": [21]},
    {"kind": "saturated", "at": [40, 41]},
    {"kind": "overheat", "at": [12], "axis": "light_elevation", "for_s": 30},
]


def finished(run: Run) -> set[int]:
    """Targets measured or skipped."""
    return set(run.target.tolist()) | set(run.skipped.tolist())


@pytest.mark.usefixtures("rigs_parsed_once")
@pytest.mark.parametrize("seed", KILL_SEEDS)
def test_kill_9_at_random_moments(
    seed: int,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
) -> None:
    files = run_files(faults=FAULTS, acquisition={"on_fault": {"retries": 1, "then": "skip"}})
    expected = uninterrupted(files)
    assert len(expected.skipped) == 0 and expected.samples["remeasured"].any()
    assert expected.of_kind("pause")
    path = tmp_path / "run.sqlite"
    rng = random.Random(seed)
    kills = runs = 0
    in_flight = 0  # most samples committed but not reported by a killed child

    def start(progress: PipeProgress) -> session.SessionResult:
        return files.start(path, progress=progress)

    def resume(progress: PipeProgress) -> session.SessionResult:
        return session.resume(path, progress=progress)

    while kills < KILLS_PER_SEED:  # one run after another until enough kills
        remove_run_file(path)
        runs += 1
        before: set[int] = set()
        while True:
            # A quarter of the kills at any time from the fork (opening, reading the run,
            # restoring, calibrating), the rest within 3 ms of the n-th target reported.
            after = 0 if rng.random() < 0.25 else rng.randint(1, 12)
            delay = rng.uniform(0.0, 0.03 if after == 0 else 0.003)
            work = resume if path.exists() else start
            child = acquire_in_child(work, kill_after=after, delay_s=delay)
            kills += child.killed
            if not path.exists():
                assert child.killed, child.last  # killed before the run file appeared
                continue
            assert integrity(path) == "ok"
            run = open_run(path)
            now = finished(run)
            new = now - before
            assert set(child.reported) <= new, "a sample reported committed was lost"
            in_flight = max(in_flight, len(new - set(child.reported)))
            assert in_flight <= 1, "more than the sample in flight"
            before = now
            if not child.killed:
                assert child.last == "done completed", child.last
                break
        assert run.complete
        assert_same_samples(run, expected)
    print(f"seed {seed}: {kills} kills in {runs} runs, {in_flight} in flight at most")


def samples_in(path: Path) -> int:
    """Samples committed in ``path`` so far (0 while it does not exist)."""
    if not path.exists():
        return 0
    try:
        conn = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True)
        try:
            return int(conn.execute("SELECT COUNT(*) FROM samples").fetchone()[0])
        finally:
            conn.close()
    except sqlite3.Error:
        return 0


def test_kill_9_of_gonio_acquire(
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
    run_gonio: Callable[..., object],
) -> None:
    """``python -m gonio acquire`` killed after its first sample, then ``gonio acquire
    --resume`` killed after its first; a last ``--resume`` completes the run."""
    files = run_files()
    path = tmp_path / "run.sqlite"
    killed = 0
    for argv in (files.cli(path), ["acquire", "--resume", str(path), "-q"]):
        had = samples_in(path)
        proc = subprocess.Popen(
            [sys.executable, "-m", "gonio", *argv],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        deadline = time.monotonic() + 60
        while samples_in(path) <= had and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        proc.kill()
        _, err = proc.communicate()
        killed += proc.returncode == -9
        assert proc.returncode in (-9, 0), err.decode()
        assert integrity(path) == "ok"
        assert samples_in(path) > had
    assert killed >= 1
    result = run_gonio("acquire", "--resume", str(path), "-q")
    assert result.returncode == 0, result.stderr  # type: ignore[attr-defined]
    assert_same_samples(open_run(path), uninterrupted(files))
