"""Ctrl-C and SIGTERM: a first signal to a running `gonio acquire` (a
forked child running `gonio.cli.main`) finishes the sample in flight, journals a pause,
exits 130 printing the resume command; the run file is reusable at once, and the resumed
run equals the uninterrupted one."""

from __future__ import annotations

import os
import random
import signal
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.acquire import observer
from gonio.cli import main
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.support.acquire import PipeProgress, RunFiles, acquire_in_child, assert_same_samples


@pytest.mark.usefixtures("rigs_parsed_once")
@pytest.mark.parametrize(("signum", "after"), [(signal.SIGINT, 3), (signal.SIGTERM, 17)])
def test_a_first_signal_finishes_the_sample_and_pauses(
    signum: int,
    after: int,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
    capfd: pytest.CaptureFixture[str],
) -> None:
    files = run_files()
    path = tmp_path / "run.sqlite"

    def acquire(progress: PipeProgress) -> int:
        observer.for_stream = lambda quiet, stream=None: progress  # type: ignore[assignment]
        return main(files.cli(path))

    capfd.readouterr()
    child = acquire_in_child(acquire, kill_after=after, kill_signal=signum)
    assert child.last == "done 130"
    err = capfd.readouterr().err.splitlines()
    assert err[-1] == f"resume with: gonio acquire --resume {path}"
    run = open_run(path)
    # Every target reported is in, and at most the one in flight beyond them.
    assert set(child.reported) <= set(run.target.tolist())
    assert len(run) <= len(child.reported) + 1
    assert run.sessions[-1].outcome == "interrupted"
    pause = run.events[-1]
    assert pause.kind == "pause" and pause.data["reason"] == "signal"
    assert pause.data["signal"] == signal.Signals(signum).name
    outcome = session.resume(path)  # at once: the lock is free, the file consistent
    assert outcome.report.outcome == "completed"
    assert_same_samples(outcome.run, uninterrupted(files))


@pytest.mark.usefixtures("rigs_parsed_once")
@pytest.mark.parametrize("seed", range(6))
def test_a_second_signal_stops_at_once(
    seed: int,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
) -> None:
    """Two SIGINTs 0.3 ms apart at a random moment: the step in flight is abandoned
    (journaled as such, with no mid-step snapshot) and redone on resume, so the resumed
    run still equals the uninterrupted one."""
    rng = random.Random(seed)
    files = run_files()
    path = tmp_path / "run.sqlite"
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        os.close(r)
        try:  # 2 ms per target: the run is still going when the signals come
            files.start(path, progress=PipeProgress(w, pause_s=0.002))
        finally:
            os._exit(0)
    os.close(w)
    reported = b""
    while reported.count(b"t ") < rng.randint(1, 20):
        reported += os.read(r, 4096)
    time.sleep(rng.uniform(0, 0.002))
    os.kill(pid, signal.SIGINT)
    time.sleep(0.0003)
    os.kill(pid, signal.SIGINT)
    while chunk := os.read(r, 4096):
        reported += chunk
    os.close(r)
    _, status = os.waitpid(pid, 0)
    assert os.WIFEXITED(status)
    run = open_run(path)
    assert run.sessions[-1].outcome == "interrupted"
    pause = run.events[-1]
    assert pause.kind == "pause" and pause.data["reason"] == "signal"
    assert ("sim_state" in pause.data) != pause.data["abandoned"]
    outcome = session.resume(path)
    assert outcome.report.outcome == "completed"
    assert_same_samples(outcome.run, uninterrupted(files))
