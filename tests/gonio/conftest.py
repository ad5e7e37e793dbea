"""Fixtures of the gonio tests: the quick plan and one folder for simulated runs, each
shared across packages; the acquisition and run-journal tests' plan and scene files and
reference runs (helpers: tests/support/acquire.py)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from gonio.planner import Plan, load_plan_source
from gonio.rig.model import Rig
from gonio.store.read import Run
from tests.conftest import CONFIGS
from tests.support.acquire import ARCH, BRUSHED, RunFiles, plan_yaml, scene_yaml

_REFERENCES: dict[tuple[str, str], Run] = {}


@pytest.fixture(scope="session")
def quick_plan() -> Plan:
    """configs/plans/quick.yaml on its rig, built once (a `Plan` is frozen, its arrays
    read-only)."""
    return load_plan_source(CONFIGS / "plans" / "quick.yaml").build()


@pytest.fixture(scope="session")
def runs_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The folder for `tests.support.runs.simulated_run`: it names a run by its specs'
    hash and reuses the file, so the modules that ask for the same run share one
    acquisition (per xdist worker). Tests read these runs and never write them."""
    folder = tmp_path_factory.getbasetemp() / "runs"
    folder.mkdir(exist_ok=True)
    return folder


@pytest.fixture
def run_files(tmp_path: Path) -> Callable[..., RunFiles]:
    """Factory: a plan file (`plan_yaml`) and a scene file (`scene_yaml`) in tmp_path."""
    made = 0

    def make(
        targets: int = 60,
        *,
        faults: list[dict[str, Any]] | None = None,
        acquisition: dict[str, Any] | None = None,
        rig: Path = ARCH,
        base: Path = BRUSHED,
    ) -> RunFiles:
        nonlocal made
        made += 1
        plan = tmp_path / f"plan{made}.yaml"
        scene = tmp_path / f"scene{made}.yaml"
        plan.write_text(plan_yaml(targets, rig=rig, acquisition=acquisition))
        scene.write_text(scene_yaml(faults, base))
        return RunFiles(plan, scene)

    return make


@pytest.fixture
def uninterrupted() -> Callable[[RunFiles], Run]:
    """The run of these files measured in one go, in memory (once per plan and scene)."""

    def run(files: RunFiles) -> Run:
        key = (files.plan.read_text(), files.scene.read_text())
        if key not in _REFERENCES:
            outcome = files.start(None)
            assert outcome.report.outcome == "completed", outcome.report
            _REFERENCES[key] = outcome.run
        return _REFERENCES[key]

    return run


@pytest.fixture
def rigs_parsed_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """`Rig.from_yaml` of given bytes memoized, so forked children share the test's
    parsed rigs and each kill costs the run, not YAML parsing (~50 ms a resume)."""
    original = Rig.from_yaml.__func__  # type: ignore[attr-defined]

    @functools.cache
    def parsed(path: str, raw: bytes, alignment_raw: bytes | None) -> Rig:
        return original(Rig, path, raw, alignment_raw)  # type: ignore[no-any-return]

    def from_yaml(
        cls: type[Rig],
        path: str | Path,
        raw: bytes | None = None,
        alignment_raw: bytes | None = None,
    ) -> Rig:
        if raw is None:
            return original(cls, path, raw, alignment_raw)  # type: ignore[no-any-return]
        return parsed(str(path), raw, alignment_raw)

    monkeypatch.setattr(Rig, "from_yaml", classmethod(from_yaml))
