"""The plan a user runs for an error target: the fastest combination of a scene that
meets it, written as a plan file (``OUTDIR/plans/SCENE.yaml``) beside a copy of the rig
it was measured with (``SCENE.rig.yaml``: the rig file's bytes, or the velocity-scaled
rig), so ``gonio acquire OUTDIR/plans/SCENE.yaml --scene SCENE_FILE`` plans exactly the
targets the sweep measured."""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any

from gonio.config import spec_text
from gonio.output import reserve_output
from gonio.planner import PlanSpec
from gonio.tradeoff.grid import Sweep
from gonio.tradeoff.plots import slug

PLANS = "plans"


def plan_paths(folder: Path, scene: str) -> tuple[Path, Path]:
    """(plan file, rig file) of ``scene``'s target plan in the output ``folder``."""
    stem = slug(scene)
    return folder / PLANS / f"{stem}.yaml", folder / PLANS / f"{stem}.rig.yaml"


def write_target_plan(
    folder: Path, sweep: Sweep, row: dict[str, Any], metric: str, target: float
) -> Path:
    """Write the plan of ``row`` (the fastest meeting ``target``) and its rig; the plan's
    path."""
    task = sweep.task(row["id"])
    plan_path, rig_path = plan_paths(folder, row["scene"])
    plan_path.parent.mkdir(exist_ok=True)
    scale = row["velocity_scale"]
    rig_text = task.rig_text
    if scale != 1.0:
        rig_text = (
            f"# {sweep.rig.source} with every axis's max velocity × {scale:g} and max "
            f"acceleration × {scale:g}² (gonio tradeoff, velocity_scale)\n"
        ).encode() + rig_text
    data = {**task.plan, "name": f"{sweep.spec.name}-{slug(row['scene'])}", "rig": rig_path.name}
    if task.budget_s is not None:  # the target the runner fitted to the time budget
        data["sampling"] = {**data["sampling"], "target": row["asked"]}
    spec = PlanSpec.model_validate(data)
    scene_file = next(s.path for s in sweep.scenes if s.name == row["scene"])
    header = (
        f"# The fastest plan of sweep {sweep.spec.name!r} ({sweep.path}) meeting {metric} ≤ "
        f"{target:g} on scene {row['scene']!r}:\n"
        f"# combination {row['id']}, {metric} {row[metric]:.4g} in {row['instrument_s']:.1f} s "
        f"of simulated instrument time (predicted {row['predicted_s']:.1f} s),\n"
        f"# reconstructed with {row['method']}, effects modelled: {row['effects']}.\n"
        f"# Run it: gonio acquire {plan_path} --scene {scene_file} -o RUN.sqlite\n"
    )
    with reserve_output(rig_path, "-o") as pending:
        pending.write_bytes(rig_text)
    with reserve_output(plan_path, "-o") as pending:
        pending.write_bytes(header.encode() + spec_text(spec))
    return plan_path


def remove_target_plan(folder: Path, scene: str) -> None:
    """Remove ``scene``'s target plan of an earlier run (it no longer applies)."""
    for path in plan_paths(folder, scene):
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
