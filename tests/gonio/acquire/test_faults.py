"""Fault paths through the simulated backend's injected faults: transient
faults retried, then skipped or aborted per the plan's ``acquisition.on_fault``; a motor
fault or a motion timeout ends the run resumable with the axes told to hold and the fault
journaled with its flags; an overheating motor pauses the run (journaled pause and
resume), or ends it ``paused`` after the timeout. In every case the devices end closed
and the run resumes to completion."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from gonio.store.read import Run, open_run
from gonio.workflows import backends, session
from sim.clock import ManualClock
from sim.virtual.devices.motors import SimMotorBus
from tests.support.acquire import RunFiles, assert_same_samples


class Watched:
    """The backends built during a test, and the calls of `SimMotorBus.stop`."""

    def __init__(self) -> None:
        self.built: list[backends.Backend] = []
        self.stops = 0

    def assert_closed(self) -> None:
        assert self.built
        for backend in self.built:
            devices = backend.devices
            assert not devices.bus.is_open and not devices.detector.is_open
            assert devices.light is None or not devices.light.is_open


@pytest.fixture
def watched(monkeypatch: pytest.MonkeyPatch) -> Watched:
    seen = Watched()
    build, stop = backends.build, SimMotorBus.stop

    def recorded(*args: Any, **kwargs: Any) -> backends.Backend:
        backend = build(*args, **kwargs)
        seen.built.append(backend)
        return backend

    def counted(bus: SimMotorBus) -> None:
        seen.stops += 1
        stop(bus)

    monkeypatch.setattr(backends, "build", recorded)
    monkeypatch.setattr(SimMotorBus, "stop", counted)
    return seen


def resumed_to_completion(path: Path, run: Run, **kwargs: Any) -> Run:
    outcome = session.resume(path, **kwargs)
    assert outcome.report.outcome == "completed", outcome.report
    done = outcome.run
    assert done.complete and len(done) + len(done.skipped) == len(done.plan)
    assert set(run.target.tolist()) <= set(done.target.tolist())
    return done


@pytest.mark.parametrize("kind", ["comm_error", "detector_error"])
def test_a_transient_fault_is_retried(
    kind: str, tmp_path: Path, run_files: Callable[..., RunFiles], watched: Watched
) -> None:
    files = run_files(20, faults=[{"kind": kind, "at": [3, 11]}])  # retries: 2 by default
    outcome = files.start(tmp_path / "run.sqlite")
    run = outcome.run
    assert outcome.report.outcome == "completed" and len(run) == 20
    retries = run.of_kind("retry")
    assert [(e.target, e.data["error"], e.data["attempt"]) for e in retries] == [
        (3, retries[0].data["error"], 1),
        (11, retries[0].data["error"], 1),
    ]
    assert retries[0].data["error"] == ("CommError" if kind == "comm_error" else "DetectorError")
    attempts = dict(zip(run.target.tolist(), run.samples["attempts"].tolist(), strict=True))
    assert attempts[3] == attempts[11] == 2 and attempts[4] == 1
    watched.assert_closed()


def test_a_transient_fault_without_retries_skips_the_target(
    tmp_path: Path, run_files: Callable[..., RunFiles], watched: Watched
) -> None:
    files = run_files(
        20,
        faults=[{"kind": "comm_error", "at": [6]}],
        acquisition={"on_fault": {"retries": 0, "then": "skip"}},
    )
    path = tmp_path / "run.sqlite"
    outcome = files.start(path)
    assert outcome.report.outcome == "completed" and outcome.report.skipped == 1
    (skip,) = outcome.run.of_kind("skip")
    assert skip.target == 6 and "CommError after 1 attempts" in skip.data["reason"]
    assert outcome.run.skipped.tolist() == [6] and len(outcome.run) == 19
    watched.assert_closed()


def test_a_transient_fault_aborts_when_the_plan_says_so(
    tmp_path: Path, run_files: Callable[..., RunFiles], watched: Watched
) -> None:
    # (An injected fault fires on a sample's first attempt only, so retries would
    # succeed: the abort is shown with none.)
    path = tmp_path / "run.sqlite"
    files = run_files(
        20,
        faults=[{"kind": "detector_error", "at": [8]}],
        acquisition={"on_fault": {"retries": 0, "then": "abort"}},
    )
    outcome = files.start(path)
    assert outcome.report.outcome == "aborted"
    run = outcome.run
    assert len(run) == 8 and run.sessions[-1].outcome == "aborted"
    (fault,) = run.of_kind("fault")
    assert fault.target == 8 and fault.data["error"] == "DetectorError"
    watched.assert_closed()
    resumed_to_completion(path, run)
    watched.assert_closed()


@pytest.mark.parametrize(
    ("fault", "error"),
    [
        (
            {
                "kind": "motor_fault",
                "at": [9],
                "axis": "detector_elevation",
                "flags": ["overload", "overheating"],
            },
            "MotorFault",
        ),
        ({"kind": "motion_timeout", "at": [9]}, "MotionTimeout"),
    ],
)
def test_a_motor_fault_ends_the_run_resumable(
    fault: dict[str, Any],
    error: str,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    watched: Watched,
) -> None:
    files = run_files(20, faults=[fault])
    path = tmp_path / "run.sqlite"
    outcome = files.start(path)
    assert outcome.report.outcome == "fault"
    run = outcome.run
    assert len(run) == 9 and run.sessions[-1].outcome == "fault"
    (event,) = run.of_kind("fault")
    assert event.target == 9 and event.data["error"] == error and "sim_state" in event.data
    if error == "MotorFault":
        assert event.data["axis"] == "detector_elevation"
        assert event.data["flags"] == ["overload", "overheating"]
    assert watched.stops >= 1  # every axis told to hold
    watched.assert_closed()
    done = resumed_to_completion(path, run)
    assert len(done) == 20 and not done.of_kind("fault")[1:]  # fired once, not again
    watched.assert_closed()


def overheat_files(run_files: Callable[..., RunFiles], timeout_min: float) -> RunFiles:
    """Motor 'light_elevation' at 80 °C for 60 s from the move into target 12; health
    checked every 10 targets (next at 20, within those 60 s), polled every 10 s."""
    return run_files(30, faults=[{"kind": "overheat", "at": [12], "axis": "light_elevation",
                                  "temperature_c": 80, "for_s": 60}],
                     acquisition={"health": {"every_samples": 10, "poll_s": 10,
                                             "pause_timeout_minutes": timeout_min}})  # fmt: skip


def test_an_overheating_motor_pauses_the_run(
    tmp_path: Path, run_files: Callable[..., RunFiles], watched: Watched
) -> None:
    outcome = overheat_files(run_files, 5.0).start(tmp_path / "run.sqlite")
    assert outcome.report.outcome == "completed"
    run = outcome.run
    (pause,) = run.of_kind("pause")
    (resume,) = [e for e in run.of_kind("resume") if e.data.get("reason") == "health"]
    assert pause.data["reason"] == "health" and "light_elevation at 80" in pause.data["problems"][0]
    assert 0 < resume.data["paused_s"] <= 60 and resume.t_s > pause.t_s
    assert watched.stops >= 1
    watched.assert_closed()


def test_a_pause_that_does_not_clear_ends_the_run_paused(
    tmp_path: Path, run_files: Callable[..., RunFiles], watched: Watched
) -> None:
    path = tmp_path / "run.sqlite"
    outcome = overheat_files(run_files, 0.25).start(path)
    assert outcome.report.outcome == "paused" and "did not clear" in outcome.report.message
    run = outcome.run
    assert len(run) == 20 and run.sessions[-1].outcome == "paused"
    watched.assert_closed()
    # The simulated motor stays hot for 60 s of the run's clock, which runs only while
    # the run does: each resume pauses again (15 s at most) until it has cooled.
    for _ in range(4):
        again = session.resume(path)
        if again.report.outcome == "completed":
            break
        assert again.report.outcome == "paused"
    done = again.run
    assert done.complete and len(done) == 30
    times = [e.t_s for e in done.events]
    assert times == sorted(times)  # each session goes on from the pause, never back
    (resumed,) = [e for e in done.of_kind("resume") if e.data.get("reason") == "health"]
    assert resumed.t_s >= 60.0  # cooled 60 s after the move into target 12
    watched.assert_closed()


def test_gonio_acquire_ends_a_faulted_run_with_exit_3(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., Any]
) -> None:
    files = run_files(20, faults=[{"kind": "motor_fault", "at": [5]}])
    path = tmp_path / "run.sqlite"
    result = run_gonio(*files.cli(path))
    assert result.returncode == 3
    ended, resume = result.stderr.splitlines()
    assert ended.startswith("gonio: the run ended early: ")
    assert resume == f"resume with: gonio acquire --resume {path}"
    assert run_gonio("acquire", "--resume", str(path), "-q").returncode == 0


class Crash(BaseException):
    """A crash at a chosen moment, in-process: nothing in the engine catches it, so the
    journal is left as a kill would leave it (the session never ended)."""


def test_a_crash_during_a_pause_resumes_as_if_uninterrupted(
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The overheated motor is part of the simulated state: a run that crashed half-way
    through the pause still waits for it to cool when it resumes."""
    files = overheat_files(run_files, 5.0)
    expected = uninterrupted(files)
    polls = 0
    sleep = ManualClock.sleep

    def crash_at_the_second_poll(clock: ManualClock, seconds: float) -> None:
        nonlocal polls
        polls += seconds == 10.0  # the pause's poll_s (settling is 0.2 s)
        if polls == 2:
            raise Crash
        sleep(clock, seconds)

    monkeypatch.setattr(ManualClock, "sleep", crash_at_the_second_poll)
    path = tmp_path / "run.sqlite"
    with pytest.raises(Crash):
        files.start(path)
    monkeypatch.setattr(ManualClock, "sleep", sleep)
    crashed = open_run(path)
    assert crashed.sessions[-1].outcome is None and crashed.of_kind("pause")
    outcome = session.resume(path)
    assert outcome.report.outcome == "completed"
    assert_same_samples(outcome.run, expected)
