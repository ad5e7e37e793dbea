"""One simulated run (noise on) shared by the export tests, acquired once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.runs import plan_spec, scene_spec, simulated_run


@pytest.fixture(scope="session")
def run_file(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(60), scene_spec("glossy_metal"))
