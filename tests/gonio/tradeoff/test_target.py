"""The target plan of a combination: a plan file the planner reads, with the
combination's plan (seeds included) and the rig it was measured with beside it (the
velocity-scaled one for a scaled combination), and the header saying where it came
from; a scene with no plan meeting the target has its old one removed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gonio.planner.files import load_plan_source
from gonio.planner.schema import PlanSpec
from gonio.tradeoff.grid import load_sweep
from gonio.tradeoff.target import plan_paths, remove_target_plan, write_target_plan
from tests.gonio.tradeoff.conftest import SMALL, write_sweep


def test_a_scaled_combination_gets_its_scaled_rig(tmp_path: Path) -> None:
    axes = {**SMALL["axes"], "velocity_scale": [2.0]}
    sweep = load_sweep(write_sweep(tmp_path, axes=axes))
    task = sweep.tasks[1]
    row = {**task.inputs, "log_rmse": 0.01, "instrument_s": 50.0, "predicted_s": 45.0}
    out = tmp_path / "out"
    out.mkdir()
    path = write_target_plan(out, sweep, row, "log_rmse", 0.02)
    assert path == plan_paths(out, "matte")[0] == out / "plans" / "matte.yaml"
    text = path.read_text(encoding="utf-8")
    assert f"combination {task.id}, log_rmse 0.01 in 50.0 s" in text
    source = load_plan_source(path)
    assert source.rig.source == out / "plans" / "matte.rig.yaml"
    np.testing.assert_allclose(source.rig.velocity, 2.0 * sweep.rig.velocity, rtol=1e-15)
    np.testing.assert_allclose(source.rig.acceleration, 4.0 * sweep.rig.acceleration, rtol=1e-15)
    expected = {**task.plan, "name": "small-matte", "rig": "matte.rig.yaml"}
    assert source.spec == PlanSpec.model_validate(expected)
    assert source.spec.sampling.seed == task.inputs["plan_seed"]
    remove_target_plan(out, "matte")
    assert not list((out / "plans").iterdir())
