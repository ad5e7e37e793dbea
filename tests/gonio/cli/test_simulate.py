"""`gonio simulate`: a plan measured on the simulated rig, end to end, as a user runs it."""

from __future__ import annotations

import csv
import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gonio.cli.simulate import reference_pose, simulate_plan
from gonio.planner import build, load_plan
from sim.scene import load_scene
from tests.gonio.rig.helpers import RIGS

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
GONIO = Path(sys.executable).with_name("gonio")


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(GONIO), *args], capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL
    )


def test_simulate_writes_the_run_and_recovers_the_brdf(tmp_path: Path) -> None:
    out = tmp_path / "run.csv"
    r = run(
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


@pytest.mark.parametrize("rig_name", list(RIGS))
def test_without_effects_the_recovered_brdf_is_exact(rig_name: str) -> None:
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = build(spec, RIGS[rig_name])
    scene = load_scene(CONFIGS / "scenes" / "glossy_metal.yaml").with_effects([])
    result = simulate_plan(plan, scene)
    np.testing.assert_allclose(result.brdf, result.truth, rtol=1e-12)
    assert reference_pose(RIGS[rig_name]).shape == (4,)


def test_bad_scene_is_one_line(tmp_path: Path) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text("name: x\nmaterial: {name: velvet}\n", encoding="utf-8")
    r = run("simulate", str(CONFIGS / "plans" / "quick.yaml"), "--scene", str(scene))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert f"{scene}:2: material.name: unknown BRDF model 'velvet'" in r.stderr


def test_saturating_reference_exposure_is_shortened() -> None:
    """At a 0.3 s plan exposure the reference standard would clip: the calibration
    halves the exposure until it does not, and the recovered BRDF stays right."""
    spec, rig = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = dataclasses.replace(build(spec, rig), exposure_s=np.full(500, 0.3))
    scene = load_scene(CONFIGS / "scenes" / "matte.yaml")
    result = simulate_plan(plan, scene)
    assert result.reference_exposure_s == 0.15
    ok = ~result.run.saturated
    assert ok.sum() > 50
    assert np.median(np.abs(result.brdf[ok] / result.truth[ok] - 1)) < 0.01


def test_drift_is_divided_out_with_the_two_reference_readings() -> None:
    spec, rig = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = build(spec, rig)
    scene = load_scene(CONFIGS / "scenes" / "matte.yaml").with_effects(
        {"source_drift": {"rate_per_hour": 0.5}}
    )
    result = simulate_plan(plan, scene)
    # Half an hour of drift per hour over a 7.5 minute run: ~6 % by the end, linear in
    # time, so interpolating the reference removes it to rounding.
    assert 0.05 < result.reference_change < 0.07
    np.testing.assert_allclose(result.brdf, result.truth, rtol=1e-9)


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
