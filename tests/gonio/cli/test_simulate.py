"""`gonio simulate`: a plan measured on the simulated rig, end to end, as a user runs it."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gonio.planner import build, load_plan
from sim.scene import load_scene
from sim.session import simulate_plan
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]


def test_simulate_writes_the_run_and_recovers_the_brdf(run_gonio: Gonio, tmp_path: Path) -> None:
    out = tmp_path / "run.csv"
    r = run_gonio(
        "simulate", str(CONFIGS / "plans" / "quick.yaml"),
        "--scene", str(CONFIGS / "scenes" / "matte.yaml"), "-o", str(out),
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "scene 'matte' (effects: shot_noise, read_noise, dark_current" in r.stdout
    with out.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 500
    brdf = np.array([float(row["brdf"]) for row in rows])
    truth = np.array([float(row["brdf_truth"]) for row in rows])
    error = np.abs(brdf / truth - 1)
    assert np.median(error) < 0.005  # shot and read noise at ~30 % of full well
    settled = np.array([float(row["settled_s"]) for row in rows])
    assert np.all(np.diff(settled) > 0)


def test_bad_scene_is_one_line(run_gonio: Gonio, tmp_path: Path) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text("name: x\nmaterial: {name: velvet}\n", encoding="utf-8")
    r = run_gonio("simulate", str(CONFIGS / "plans" / "quick.yaml"), "--scene", str(scene))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert f"{scene}:2: material.name: unknown BRDF model 'velvet'" in r.stderr


def test_notes_when_the_scene_and_the_rig_disagree() -> None:
    from gonio.cli.simulate import render
    from sim.scene import Scene

    spec, rig = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = build(spec, rig)
    base = load_scene(CONFIGS / "scenes" / "seed000_specular.yaml")
    result = simulate_plan(plan, base)
    text = render(result)
    assert "see past the sample's edge (θo > 33.6°)" in text
    assert "differ from the rig file's" not in text
    bigger = Scene.model_validate({**base.model_dump(), "sample": {"diameter_mm": 40}})
    text = render(simulate_plan(plan, bigger))
    assert "the scene's sample diameter 40 mm (rig 30 mm) differ from the rig file's" in text
