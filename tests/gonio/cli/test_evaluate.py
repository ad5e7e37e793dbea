"""`gonio evaluate`: a small simulated run scored by the naive reference, as a table and
as JSON, against the scene, a model and another run; and its one-line errors."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.reconstruct.metrics import METRICS, REGIONS
from gonio.reconstruct.testset import DEFAULT_SIZE
from tests.conftest import CliResult
from tests.support.runs import plan_spec, scene_spec, simulated_run

Gonio = Callable[..., CliResult]


@pytest.fixture(scope="module")
def run(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(300), scene_spec("matte", noise=False))


def test_the_table_has_a_row_per_region(run_gonio: Gonio, run: Path) -> None:
    r = run_gonio("evaluate", str(run), "--method", "naive")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == f"naive (hybrid, 300 samples of {run}) vs the scene of {run}"
    assert lines[1].startswith(f"test set: {DEFAULT_SIZE} pairs (seed 14)")
    assert lines[2].startswith("scored: every pair (outside the support: nearest-node fill)")
    assert lines[3].split() == ["region", "pairs", "coverage", "log-RMSE", "cos", "log-RMSE",
                                "rel", "RMSE", "rel", "median", "rel", "p95"]  # fmt: skip
    assert [line.split()[0] for line in lines[4:]] == ["all", *REGIONS]


def test_json_gives_every_metric_and_the_naive_floor_is_close_on_a_matte_run(
    run_gonio: Gonio, run: Path
) -> None:
    r = run_gonio("evaluate", str(run), "--method", "naive", "--json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    regions = data["regions"]
    assert list(regions) == ["all", *REGIONS]
    assert regions["all"]["pairs"] == DEFAULT_SIZE
    assert sum(regions[name]["pairs"] for name in REGIONS) == DEFAULT_SIZE
    assert set(METRICS) <= set(regions["all"])
    assert 0.5 < regions["all"]["coverage"] < 1.0
    assert 0 < regions["all"]["log_rmse"] < 0.05  # a smooth matte paint, noise-free
    assert regions["all"]["rel_median"] < 0.02


def test_a_model_truth_and_a_run_truth(run_gonio: Gonio, run: Path) -> None:
    scene = json.loads(run_gonio("evaluate", str(run), "--method", "naive", "--json").stdout)
    model = "cook_torrance:alpha=0.5,distribution=ggx,fresnel=schlick,f0=0.04,kd=0.6"
    r = run_gonio("evaluate", str(run), "--method", "naive", "--truth", model, "--json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["regions"] == scene["regions"]  # the scene's own material
    r = run_gonio("evaluate", str(run), "--method", "naive", "--truth", str(run), "--json")
    assert r.returncode == 0, r.stderr
    itself = json.loads(r.stdout)
    assert itself["truth"] == f"the reconstruction of {run}"
    assert itself["regions"]["all"]["coverage"] == 1.0  # only where the truth has data
    assert all(itself["regions"]["all"][m] == 0.0 for m in METRICS)


def test_another_parametrization(run_gonio: Gonio, run: Path) -> None:
    r = run_gonio("evaluate", str(run), "--method", "naive", "--parametrization", "spherical")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"naive (spherical, 300 samples of {run})")


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--truth", "velvet"], "unknown BRDF model 'velvet'"),
        (["--truth", "lambert:albedo=2"], "a reflectance is at most 1"),
        (["--parametrization", "polar"], "unknown parametrization 'polar'"),
        (["--method", "velvet"], "method 'velvet'"),
        (["--method", "lines"], "method 'lines' needs samples on lines"),
    ],
)
def test_mistakes_are_one_line_and_exit_2(
    run_gonio: Gonio, run: Path, args: list[str], says: str
) -> None:
    method = [] if "--method" in args else ["--method", "naive"]
    r = run_gonio("evaluate", str(run), *method, *args)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.startswith("gonio: error: ") and says in r.stderr
    assert r.stderr.count("\n") == 1


def test_a_missing_run_file_is_one_line(run_gonio: Gonio, tmp_path: Path) -> None:
    r = run_gonio("evaluate", str(tmp_path / "none.sqlite"), "--method", "naive")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "none.sqlite" in r.stderr


def test_every_method_scores_the_demo_like_run(run_gonio: Gonio, run: Path) -> None:
    for method in ("naive", "linear", "rbf", "model+residual"):
        r = run_gonio("evaluate", str(run), "--method", method, "--json")
        assert r.returncode == 0, r.stderr
        scores = json.loads(r.stdout)["regions"]["all"]
        assert 0.0 <= scores["log_rmse"] < 0.2, (method, scores)


def test_every_pair_is_scored_with_the_fill_stated_or_only_the_supported_ones(
    run_gonio: Gonio, run: Path
) -> None:
    r = run_gonio("evaluate", str(run), "--method", "linear")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[2] == (
        "scored: every pair (outside the support: nearest fill); coverage: the share inside "
        "the support"
    )
    every = json.loads(run_gonio("evaluate", str(run), "--method", "linear", "--json").stdout)
    assert every["only_supported"] is False and every["fill"] == "nearest"
    overall = every["regions"]["all"]
    assert overall["scored"] == overall["pairs"] == DEFAULT_SIZE
    assert 0.5 < overall["coverage"] < 1.0
    r = run_gonio("evaluate", str(run), "--method", "linear", "--only-supported", "--json")
    assert r.returncode == 0, r.stderr
    inside = json.loads(r.stdout)
    assert inside["only_supported"] is True
    assert inside["regions"]["all"]["scored"] == round(overall["coverage"] * DEFAULT_SIZE)
    assert inside["regions"]["all"]["coverage"] == overall["coverage"]


def test_a_model_fill_without_a_model_is_one_line(run_gonio: Gonio, run: Path) -> None:
    r = run_gonio("evaluate", str(run), "--method", "linear", "--extrapolate", "model")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "needs a model" in r.stderr
