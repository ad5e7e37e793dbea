"""Resume: a run stopped any number of times (graceful stops here; kills
in tests/gonio/store/test_crash.py) and resumed equals the uninterrupted run bit for bit;
``--resume`` measures exactly the missing targets; it refuses a plan, rig or scene file
changed since the run started unless ``--force``."""

from __future__ import annotations

import contextlib
import json
import random
import signal
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio.acquire.signals import RunInterrupted, StopRequests
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.conftest import CliResult
from tests.support.acquire import ARCH, RunFiles, assert_same_samples, plan_yaml

#: Each resume parses the run's stored rig: once per test is enough.
pytestmark = pytest.mark.usefixtures("rigs_parsed_once")


class StopAfter:
    """A progress that asks the run to stop (as a first Ctrl-C would, through
    `StopRequests.request`) after ``n`` targets, or twice (a second Ctrl-C) if
    ``twice``."""

    def __init__(self, n: int, stops: list[StopRequests], *, twice: bool = False) -> None:
        self.n, self.stops, self.twice = n, stops, twice

    def start(self, plan: object, todo: np.ndarray) -> None:
        pass

    def advance(self, done: int) -> None:
        if done == self.n:
            self.stops[-1].request(signal.SIGTERM)
            if self.twice:
                self.stops[-1].request(signal.SIGINT)

    def close(self) -> None:
        pass


@pytest.fixture
def stops(monkeypatch: pytest.MonkeyPatch) -> list[StopRequests]:
    """The `StopRequests` of each session started, newest last."""
    made: list[StopRequests] = []

    class Recorded(StopRequests):
        def __init__(self) -> None:
            super().__init__()
            made.append(self)

    monkeypatch.setattr(session, "StopRequests", Recorded)
    return made


def stop_and_resume(path: Path, files: RunFiles, stops: list[StopRequests], seed: int) -> Run:
    """Start the run, stop it after a random number of targets, resume, and again until
    it completes; the run file as it ends."""
    rng = random.Random(seed)
    first = True
    while True:
        progress = StopAfter(rng.randint(1, 9), stops, twice=rng.random() < 0.3)
        try:
            if first:
                outcome = files.start(path, progress=progress)
            else:
                outcome = session.resume(path, progress=progress)
        except RunInterrupted:
            run = open_run(path)
            assert run.sessions[-1].outcome == "interrupted"
            pause = run.events[-1]
            assert pause.kind == "pause" and pause.data["abandoned"] == progress.twice
            assert ("sim_state" in pause.data) != progress.twice  # abandoned: redone
            first = False
            continue
        assert outcome.report.outcome == "completed"
        return outcome.run


@pytest.mark.parametrize("seed", [0, 1])
def test_stopped_and_resumed_equals_uninterrupted(
    seed: int,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    uninterrupted: Callable[[RunFiles], Run],
    stops: list[StopRequests],
) -> None:
    files = run_files(
        faults=[{"kind": "comm_error", "at": [4, 20]}, {"kind": "saturated", "at": [9]}]
    )
    run = stop_and_resume(tmp_path / "run.sqlite", files, stops, seed)
    assert len(run.sessions) > 5
    assert_same_samples(run, uninterrupted(files))


def test_resume_measures_exactly_the_missing_targets(
    tmp_path: Path, run_files: Callable[..., RunFiles], stops: list[StopRequests]
) -> None:
    files = run_files(
        40,
        faults=[{"kind": "comm_error", "at": [5]}],
        acquisition={"on_fault": {"retries": 0, "then": "skip"}},
    )
    path = tmp_path / "run.sqlite"
    with pytest.raises(RunInterrupted):
        files.start(path, progress=StopAfter(12, stops))
    before = open_run(path)
    assert len(before) == 11 and before.skipped.tolist() == [5]  # stream index = target
    missing = before.missing()
    outcome = session.resume(path)
    after = outcome.run
    resumed = after.target[after.samples["session"] == 2]
    np.testing.assert_array_equal(np.sort(resumed), np.sort(missing))
    assert set(after.skipped.tolist()) == set(before.skipped.tolist())
    assert len(after) + len(after.skipped) == len(after.plan)
    # The skipped target once its cause is gone (in the simulation, a scene without the
    # fault: an injected fault fires again at a skipped target measured in a new session).
    fixed = tmp_path / "fixed.yaml"
    fixed.write_text(files.scene.read_text().split("faults:")[0])
    again = session.resume(path, scene_path=fixed, force=True, retry_skipped=True).run
    assert again.target[again.samples["session"] == 4].tolist() == before.skipped.tolist()
    assert len(again) == len(again.plan) and again.complete
    nothing = session.resume(path).run  # a completed run: nothing measured, no reading
    assert len(nothing) == len(again.plan)
    assert len(nothing.of_kind("calibration")) == len(again.of_kind("calibration"))


@pytest.mark.parametrize("changed", ["plan", "rig", "scene"])
def test_resume_refuses_a_changed_file(
    changed: str,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    stops: list[StopRequests],
    run_gonio: Callable[..., CliResult],
) -> None:
    rig = tmp_path / "rig.yaml"
    rig.write_bytes(ARCH.read_bytes())
    files = run_files(30, rig=rig)
    path = tmp_path / "run.sqlite"
    with pytest.raises(RunInterrupted):
        files.start(path, progress=StopAfter(5, stops))
    edited = {"plan": files.plan, "rig": rig, "scene": files.scene}[changed]
    edited.write_text(edited.read_text() + "# edited\n")
    size = path.stat().st_size

    refused = run_gonio("acquire", "--resume", str(path), "-q")
    assert refused.returncode == 2
    assert refused.stdout == ""
    (line,) = refused.stderr.splitlines()
    assert str(edited) in line and f"the {changed} file changed" in line and "--force" in line
    run = open_run(path)
    assert len(run) == 5 and len(run.sessions) == 1  # nothing measured, nothing journaled
    assert path.stat().st_size == size

    forced = run_gonio("acquire", "--resume", str(path), "--force", "-q")
    assert forced.returncode == 0, forced.stderr
    run = open_run(path)
    assert run.complete and len(run) == 30
    assert run.sessions[1].outcome == "forced" and run.sessions[1].info["forced"] == [changed]


def test_plan_yaml_is_what_the_tests_use() -> None:
    assert "every_samples: 15" in plan_yaml()


@pytest.mark.parametrize("edited", ["plan", "rig", "scene"])
def test_resume_refuses_a_run_file_whose_stored_text_was_edited(
    edited: str,
    tmp_path: Path,
    run_files: Callable[..., RunFiles],
    stops: list[StopRequests],
    run_gonio: Callable[..., CliResult],
) -> None:
    """The files on disk are untouched, the journal's copy of one is not: its hash no
    longer matches the one the run recorded, and the run is refused, even with --force."""
    files = run_files(30)
    path = tmp_path / "run.sqlite"
    with pytest.raises(RunInterrupted):
        files.start(path, progress=StopAfter(5, stops))
    with contextlib.closing(sqlite3.connect(path)) as conn:
        (value,) = conn.execute(
            "SELECT value FROM meta WHERE key = ?", (f"{edited}_text",)
        ).fetchone()
        text = json.loads(value) + "# edited in the journal\n"
        conn.execute(
            "UPDATE meta SET value = ? WHERE key = ?", (json.dumps(text), f"{edited}_text")
        )
        conn.commit()
    for force in ((), ("--force",)):
        refused = run_gonio("acquire", "--resume", str(path), "-q", *force)
        assert refused.returncode == 2 and refused.stderr.count("\n") == 1, refused.stderr
        assert f"the stored {edited} text does not match" in refused.stderr
    assert len(open_run(path)) == 5
