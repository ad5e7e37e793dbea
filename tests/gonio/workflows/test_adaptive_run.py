"""The adaptive strategy on the engine: a survey pass, then a second pass
planned from the survey's journal and stored in the run; killed anywhere, the run
resumes to the same samples, bit for bit, as one measured in one go."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.planner import adaptive
from gonio.store.read import Run, open_run
from gonio.workflows import session
from tests.support.acquire import (
    ARCH,
    RunFiles,
    acquire_in_child,
    assert_same_samples,
    integrity,
    scene_yaml,
)

SURVEY = 20
TARGET = 44


@pytest.fixture(autouse=True)
def fewer_measure_pairs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The test measure estimated from 2¹⁵ pairs (a second less per second pass)."""
    monkeypatch.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)


@pytest.fixture
def adaptive_files(tmp_path: Path) -> RunFiles:
    spec = {
        "name": "adaptive",
        "rig": str(ARCH),
        "parametrization": "rusinkiewicz",
        "sampling": {
            "strategy": "adaptive",
            "target": TARGET,
            "seed": 1,
            "adaptive": {"survey": SURVEY, "model": "lambert+beckmann", "edge": 0.1},
        },
        "exposure": {"seconds": 0.05},
        "time_budget_s": 5,
        "acquisition": {"calibration": {"every_samples": 15, "averages": 4}},
    }
    plan = tmp_path / "plan.yaml"
    plan.write_text(yaml.safe_dump(spec, sort_keys=False))
    scene = tmp_path / "scene.yaml"
    scene.write_text(scene_yaml())
    return RunFiles(plan, scene)


def test_two_passes_in_one_run(
    adaptive_files: RunFiles, uninterrupted: Callable[[RunFiles], Run]
) -> None:
    survey, _, _ = adaptive_files.files()
    assert survey.is_survey and len(survey) == SURVEY
    run = uninterrupted(adaptive_files)
    assert run.complete and len(run.plan) == TARGET and len(run) == TARGET
    # The survey's targets keep their places; the second pass follows them.
    np.testing.assert_array_equal(run.plan.coords[:SURVEY], survey.coords, strict=True)
    (event,) = run.of_kind("second_pass")
    assert event.data["placed"] == run.plan.summary.second_pass  # adaptive or uniform, and why
    assert run.plan.summary.second_pass.startswith(("adaptive (floor", "uniform: "))
    assert [s.outcome for s in run.sessions] == ["completed", "completed"]


@pytest.mark.usefixtures("rigs_parsed_once")
def test_killed_in_either_pass_resumes_bit_identically(
    tmp_path: Path, adaptive_files: RunFiles, uninterrupted: Callable[[RunFiles], Run]
) -> None:
    expected = uninterrupted(adaptive_files)
    # Killed in the survey, just after it (before or after the second pass is stored),
    # and in the second pass; each time the run resumes from its journal.
    for kill_after in (8, SURVEY, SURVEY + 1, 33):
        path = tmp_path / f"run{kill_after}.sqlite"
        child = acquire_in_child(
            lambda progress, p=path: adaptive_files.start(p, progress=progress),
            kill_after=kill_after,
            hold=True,
        )
        assert child.killed and integrity(path) == "ok"
        assert not open_run(path).complete
        outcome = session.resume(path)
        assert outcome.report.outcome == "completed"
        run = open_run(path)
        assert run.complete and len(run.plan) == TARGET
        assert_same_samples(run, expected)
