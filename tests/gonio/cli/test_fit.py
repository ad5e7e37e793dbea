"""`gonio fit`: the table, --json, the material file a scene reads, and one-line errors."""

from __future__ import annotations

import contextlib
import io
import json
import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.scene import Scene
from tests.support.runs import plan_spec, scene_spec, simulated_run


@pytest.fixture(scope="module")
def runs(runs_dir: Path) -> dict[str, Path]:
    """A matte run, and gold seen in the r, g and b bands (150 targets each)."""
    plan = plan_spec(150) | {"max_moves": 0, "kicks": 0}
    gold = {"name": "cook_torrance", "alpha": 0.1, "fresnel": "schlick", "f0": [0.95, 0.7, 0.3]}
    out = {}
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        out["matte"] = simulated_run(runs_dir, plan, scene_spec("matte", noise=True, seed=3))
        for j, band in enumerate("rgb"):
            scene = scene_spec(
                "glossy_metal", material=gold, effects=["shot_noise"], band=band, seed=30 + j
            )
            out[band] = simulated_run(runs_dir, plan, scene)
    return out


def test_the_table_names_parameters_chi_square_and_regions(runs, run_gonio):
    r = run_gonio("fit", str(runs["matte"]), "--model", "lambert+ggx")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("fit lambert+ggx to ") and "150 samples, 3 parameters" in lines[0]
    for name in ("lambert.albedo", "ggx.alpha", "ggx.f0", "reduced chi-square"):
        assert any(line.strip().startswith(name) for line in lines), name
    for region in ("mirror", "retro", "grazing", "rest"):
        assert any(line.split()[:1] == [region] for line in lines), region


def test_json_and_the_material_file_a_scene_can_use(runs, run_gonio, tmp_path):
    out = tmp_path / "fitted.yaml"
    r = run_gonio("fit", str(runs["matte"]), "--model", "lambert+ggx", "--json", "-o", str(out))
    assert r.returncode == 0, r.stderr
    figures = json.loads(r.stdout)
    albedo = figures["params"]["lambert.albedo"]
    assert albedo["value"] == pytest.approx(0.6, abs=5 * albedo["stderr"] + 2e-3)
    assert set(figures["regions"]) == {"mirror", "retro", "grazing", "rest"}
    assert 0.5 < figures["chi2_red"] < 2.0
    material = yaml.safe_load(out.read_text())
    assert material["name"] == "sum" and out.read_text().startswith("# gonio fit --model")
    scene = Scene.model_validate(scene_spec("matte", material=material))
    wi, wo = np.array([0.0, 0.3, 0.954]), np.array([0.5, 0.0, 0.866])
    truth = Scene.model_validate(scene_spec("matte")).material.model()
    assert scene.material.model().eval(wi, wo) == pytest.approx(truth.eval(wi, wo), rel=1e-3)


def test_three_band_runs_make_an_rgb_fit(runs, run_gonio):
    bands = [str(runs[b]) for b in "rgb"]
    r = run_gonio("fit", *bands, "--model", "ggx", "--json", "--starts", "2", "--seed", "1")
    assert r.returncode == 0, r.stderr
    params = json.loads(r.stdout)["params"]
    assert list(params) == ["ggx.alpha", "ggx.f0[r]", "ggx.f0[g]", "ggx.f0[b]"]
    f0 = [params[f"ggx.f0[{c}]"]["value"] for c in "rgb"]
    assert f0 == pytest.approx([0.95, 0.7, 0.3], abs=0.01)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--model", "lambert+gx"], "unknown family 'gx'"),
        (["--model", "ggx:alpha"], "expected KEY=VALUE"),
        (["--model", "ggx", "--starts", "0"], "starting points in [1, 1,000], got '0'"),
        (["--model", "ggx", "--starts", "1000000000"], "in [1, 1,000], got '1000000000'"),
        (["--model", "ggx", "--seed", "-1"], "--seed: expected a whole number ≥ 0 below 2**63"),
        (["EXTRA", "--model", "ggx"], "expected one run, or three"),
    ],
)
def test_mistakes_are_one_line_with_exit_code_2(runs, run_gonio, args, words):
    r = run_gonio("fit", str(runs["matte"]), *args)
    assert r.returncode == 2
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_a_missing_run_and_bands_out_of_order_are_one_line(runs, run_gonio, tmp_path):
    r = run_gonio("fit", str(tmp_path / "none.sqlite"), "--model", "ggx")
    assert r.returncode == 2 and "no such run file" in r.stderr
    swapped = [str(runs[b]) for b in "grb"]
    r = run_gonio("fit", *swapped, "--model", "ggx")
    assert r.returncode == 2 and "r, g and b bands" in r.stderr


def test_a_run_without_calibration_is_one_line_naming_it(runs, run_gonio, tmp_path):
    copy = tmp_path / "uncalibrated.sqlite"
    shutil.copyfile(runs["matte"], copy)
    with contextlib.closing(sqlite3.connect(copy)) as db, db:
        db.execute("DELETE FROM events WHERE kind = 'calibration'")
    r = run_gonio("fit", str(copy), "--model", "ggx")
    assert r.returncode == 2
    assert (
        r.stderr.strip()
        == f"gonio: error: {copy}: the run has no calibration reading: no BRDF can be derived"
    )


def test_an_invalid_material_is_not_written(runs, run_gonio, tmp_path):
    """Lambert + a Fresnel lobe fixed at f0 = 1 exceeds energy conservation: refused."""
    out = tmp_path / "m.yaml"
    r = run_gonio("fit", str(runs["matte"]), "--model", "lambert+ggx:f0=1", "-o", str(out))
    assert r.returncode == 2 and "not a valid material" in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []
