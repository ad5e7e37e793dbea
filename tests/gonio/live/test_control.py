"""Pause, resume and stop requests posted beside a run file while a forked child
acquires it: the engine acts between targets, journals who asked, a paused run
measures nothing until resumed, a stopped one ends resumable, and either way the run
equals the uninterrupted one."""

from __future__ import annotations

import os
import signal
import stat
import time
from collections.abc import Callable
from datetime import datetime
from pathlib import Path

import pytest

from gonio.acquire import control
from gonio.live.model import LiveRun
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.support.acquire import PipeProgress, RunFiles, assert_same_samples


def _child(files: RunFiles, path: Path, pause_s: float) -> int:
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        code = 0
        try:
            files.start(path, progress=PipeProgress(os.open(os.devnull, os.O_WRONLY), pause_s))
        except KeyboardInterrupt:
            code = 130
        except BaseException:
            code = 1
        finally:
            os._exit(code)
    return pid


def _until(check: Callable[[], bool], timeout_s: float = 30.0) -> None:
    give_up = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < give_up, "timed out"
        time.sleep(0.02)


def _count(path: Path) -> int:
    return len(open_run(path)) if path.exists() else 0


@pytest.mark.usefixtures("rigs_parsed_once")
def test_pause_then_resume_continues_the_run(
    tmp_path: Path, run_files: Callable[..., RunFiles], uninterrupted: Callable[[RunFiles], Run]
) -> None:
    files = run_files(40)
    path = tmp_path / "run.sqlite"
    pid = _child(files, path, pause_s=0.01)
    _until(lambda: _count(path) >= 5)
    control.post_request(path, "pause", "test at 127.0.0.1")
    live = LiveRun(path)
    _until(lambda: live.refresh() is not None and live.state() == "paused")
    held = _count(path)
    time.sleep(0.3)
    assert _count(path) == held  # nothing measured while paused
    assert live.writing
    control.post_request(path, "resume", "test")
    _, status = os.waitpid(pid, 0)
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
    run = open_run(path)
    assert run.complete
    pause, resume = (e for e in run.events if e.data.get("reason") == "request")
    assert pause.kind == "pause" and pause.data["by"] == "test at 127.0.0.1"
    assert resume.kind == "resume" and resume.data["paused_s"] >= 0.3
    assert "sim_state" in pause.data
    assert_same_samples(run, uninterrupted(files))
    live.refresh()
    assert live.state() == "completed"
    # The rate (and so the ETA) counts the wall time the run was acquiring, not paused.
    utc = [datetime.fromisoformat(u).timestamp() for u in run.samples["utc"]]
    held = datetime.fromisoformat(resume.utc) - datetime.fromisoformat(pause.utc)
    active = utc[-1] - utc[0] - held.total_seconds()
    assert live.rate_per_s() == pytest.approx((len(utc) - 1) / active, rel=1e-6)


@pytest.mark.usefixtures("rigs_parsed_once")
def test_stop_ends_resumable_as_a_first_ctrl_c(
    tmp_path: Path, run_files: Callable[..., RunFiles], uninterrupted: Callable[[RunFiles], Run]
) -> None:
    files = run_files(40)
    path = tmp_path / "run.sqlite"
    pid = _child(files, path, pause_s=0.01)
    _until(lambda: _count(path) >= 5)
    control.post_request(path, "pause", "a")
    control.post_request(path, "stop", "b")  # stops a paused run too
    _, status = os.waitpid(pid, 0)
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 130
    run = open_run(path)
    assert run.sessions[-1].outcome == "interrupted"
    last = run.events[-1]
    assert last.kind == "stop" and last.data["reason"] == "request"
    assert not [e for e in run.of_kind("pause") if e.data.get("action") == "stop"]
    assert "sim_state" in last.data  # a resumed simulation starts from it
    assert last.data["action"] == "stop" and last.data["by"] == "b"
    assert LiveRun(path).state() == "stopped"
    outcome = session.resume(path)  # an old stop request does not act on a new session
    assert outcome.report.outcome == "completed"
    assert_same_samples(outcome.run, uninterrupted(files))


def test_the_token_is_owner_only_and_kept(tmp_path: Path) -> None:
    path = tmp_path / "run.sqlite"
    token = control.issue_token(path)
    assert len(token) >= 40
    mode = stat.S_IMODE(os.stat(control.token_path(path)).st_mode)
    assert mode == 0o600
    assert control.issue_token(path) == token  # a resumed run keeps its token
    os.chmod(control.token_path(path), 0o644)  # readable by others: not trusted, replaced
    assert control.read_token(path) is None
    assert control.issue_token(path) != token


def test_requests_are_read_once_and_garbage_ignored(tmp_path: Path) -> None:
    path = tmp_path / "run.sqlite"
    control.post_request(path, "pause", "old")
    reader = control.ControlRequests(path)
    assert reader.poll() == []  # posted before the session started
    with open(control.requests_path(path), "a") as f:
        f.write('{"action": "explode"}\nnot json\n{"action": "res')
    assert reader.poll() == []
    with open(control.requests_path(path), "a") as f:
        f.write('ume", "by": "x"}\n')
    assert [r.action for r in reader.poll()] == ["resume"]
    assert reader.poll() == []
    assert control.ControlRequests(None).poll() == []
    stop = control.StopRequested(control.Request("stop", "x", "now", "1"))
    assert isinstance(stop, KeyboardInterrupt) and stop.signum == signal.SIGINT
    assert not stop.abandoned
