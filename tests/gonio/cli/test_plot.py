"""`gonio plot`: each kind drawn from a small simulated run with the naive reference, its
data the reconstruction's and the truth's values (checked by capturing what is drawn),
a whole PNG of the figure's size; and its one-line errors, before any work."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio import params
from gonio.analysis.measured import Measured
from gonio.plots import error, polar, samples, slices
from gonio.reconstruct.naive import NaiveReconstruction
from tests.conftest import CliResult
from tests.support.figures import pixels, png_size
from tests.support.runs import plan_spec, scene_spec, simulated_run

Gonio = Callable[..., CliResult]


@pytest.fixture(scope="module")
def run(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(300), scene_spec("glossy_metal"))


@pytest.fixture(scope="module")
def measured(run: Path) -> Measured:
    return Measured.from_run(str(run))


@pytest.fixture
def drawn(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """What each kind's ``draw`` was given (the real ``draw`` still runs)."""
    seen: dict[str, Any] = {}
    for module in (slices, polar, samples, error):
        real = module.draw

        def spy(data: Any, path: Any, *, format: str | None = None, _real: Any = real) -> None:
            seen["data"] = data
            _real(data, path, format=format)

        monkeypatch.setattr(module, "draw", spy)
    return seen


def test_slices_are_the_reconstruction_at_the_inverse_mapped_pairs(
    run_gonio: Gonio, run: Path, measured: Measured, drawn: dict[str, Any], tmp_path: Path
) -> None:
    out = tmp_path / "slices.png"
    r = run_gonio("plot", str(run), "--kind", "slices", "--method", "naive",
                  "--phi-k", "20", "90", "-o", str(out))  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert r.stdout == f"drew the slices of {run} in {out}\n"
    data: slices.Slices = drawn["data"]
    naive = NaiveReconstruction(measured)
    assert [s.angle for s in data.rows[0]] == [math.radians(20.0), math.radians(90.0)]
    for row in data.rows:
        for s in row:
            p = params.get(s.parametrization)
            wi, wo = p.inverse_iso(s.coords[s.valid])
            np.testing.assert_array_equal(s.f[s.valid], naive.eval(wi, wo))
            np.testing.assert_array_equal(s.supported[s.valid], naive.supported(wi, wo))
            assert s.supported.any() and not s.supported[s.valid].all()
    assert png_size(out) == pixels(slices.figure_size(data))


def test_polar_draws_the_scene_as_the_truth_and_the_samples_near_each_plane(
    run_gonio: Gonio, run: Path, measured: Measured, drawn: dict[str, Any], tmp_path: Path
) -> None:
    out = tmp_path / "polar.png"
    r = run_gonio("plot", str(run), "--kind", "polar", "--method", "naive",
                  "--theta-i", "20", "40", "-o", str(out))  # fmt: skip
    assert r.returncode == 0, r.stderr
    data: polar.Polar = drawn["data"]
    truth = measured.scene_truth()
    assert data.truth_label == f"the scene of {run}"
    for c, theta_i in zip(data.curves, (20.0, 40.0), strict=True):
        assert c.theta_i == math.radians(theta_i)
        assert c.truth is not None
        np.testing.assert_array_equal(c.truth, truth(c.wi, c.wo))
        np.testing.assert_array_equal(c.surface, NaiveReconstruction(measured).eval(c.wi, c.wo))
        near, _ = polar.near_plane(measured.wi, measured.wo, c.theta_i, math.radians(5.0))
        assert len(c.sample_f) == np.count_nonzero(near) > 0
        np.testing.assert_array_equal(c.sample_f, measured.f[near])
        np.testing.assert_array_equal(c.sample_sigma, measured.sigma[near])
    mirror = np.argmin(np.abs(data.curves[1].theta_o - math.radians(40.0)))  # on the grid
    assert np.argmax(data.curves[1].truth) == mirror  # type: ignore[arg-type]
    assert png_size(out) == pixels(polar.FIGSIZE)


def test_coverage_by_residual_against_a_model(
    run_gonio: Gonio, run: Path, measured: Measured, drawn: dict[str, Any], tmp_path: Path
) -> None:
    out = tmp_path / "coverage.png"
    model = "lambert:albedo=0.5"
    r = run_gonio("plot", str(run), "--kind", "coverage", "--colour", "residual",
                  "--truth", model, "-o", str(out))  # fmt: skip
    assert r.returncode == 0, r.stderr
    data: samples.Coverage = drawn["data"]
    np.testing.assert_allclose(data.colour, (measured.f - 0.5 / math.pi) / measured.sigma)
    np.testing.assert_array_equal(
        data.coords, params.get("hybrid").forward_iso(measured.wi, measured.wo)
    )
    assert png_size(out) == pixels(samples.FIGSIZE)


def test_error_is_the_evaluations_test_set_by_region(
    run_gonio: Gonio, run: Path, drawn: dict[str, Any], tmp_path: Path
) -> None:
    import json

    out = tmp_path / "error.png"
    r = run_gonio("plot", str(run), "--kind", "error", "--method", "naive", "-o", str(out))
    assert r.returncode == 0, r.stderr
    data: error.Errors = drawn["data"]
    scored = json.loads(run_gonio("evaluate", str(run), "--method", "naive", "--json").stdout)
    for name, region in scored["regions"].items():
        assert data.scores[name].count == region["scored"]
        assert data.scores[name].log_rmse == pytest.approx(region["log_rmse"], rel=1e-12)
    assert png_size(out) == pixels(error.FIGSIZE)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--kind", "slices", "--phi-k", "200"], "--phi-k 200: expected an angle in degrees"),
        (["--theta-i", "85"], "--theta-i 85: expected an angle in degrees in [0, 80]"),
        (["--theta-i", "nan"], "--theta-i: expected a finite angle in degrees, got 'nan'"),
        (["--kind", "slices", "--theta-i", "1e300"], "--theta-i applies to --kind polar, not"),
        (["--phi-k", "30"], "--phi-k applies to --kind slices, not to --kind polar"),
        (["--parametrization", "polar"], "unknown parametrization 'polar'"),
        (["--method", "nope"], "method 'nope'"),
        (["--kind", "error", "--truth", "nope:x=1"], "truth 'nope:x=1'"),
    ],
)
def test_bad_input_is_one_line_and_no_figure(
    run_gonio: Gonio, run: Path, tmp_path: Path, args: list[str], message: str
) -> None:
    out = tmp_path / "f.png"
    kind = [] if "--kind" in args else ["--kind", "polar"]
    r = run_gonio("plot", str(run), *kind, *args, "-o", str(out))
    assert r.returncode == 2
    assert r.stderr.startswith("gonio: error: ") and message in r.stderr
    assert len(r.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_a_format_matplotlib_cannot_write_and_a_missing_run(
    run_gonio: Gonio, run: Path, tmp_path: Path
) -> None:
    r = run_gonio("plot", str(run), "--kind", "slices", "-o", str(tmp_path / "f.xyz"))
    assert r.returncode == 2
    assert "-o " in r.stderr and "matplotlib cannot write '.xyz' figures" in r.stderr
    r = run_gonio(
        "plot", str(tmp_path / "none.sqlite"), "--kind", "coverage", "-o", str(tmp_path / "f.png")
    )
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_kind_and_output_are_required(run_gonio: Gonio, run: Path) -> None:
    r = run_gonio("plot", str(run), "-o", "x.png")
    assert r.returncode == 2 and "--kind" in r.stderr
    r = run_gonio("plot", str(run), "--kind", "pie", "-o", "x.png")
    assert r.returncode == 2 and "invalid choice: 'pie'" in r.stderr
