"""An export that fills a grid (MERL, RGL, factored, HDF5 --grid) of a run whose samples
support less than `MIN_SUPPORTED` of it, or of fewer samples than one simplex of its
coordinates holds, is refused in one line giving the share (or the count) and the
minimum, nothing written; ``allow_sparse`` writes it with a warning giving the share."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.errors import GonioError
from gonio.export import MIN_SUPPORTED, Options, export
from tests.conftest import CliResult
from tests.support.process import listing, refused
from tests.support.runs import plan_spec, scene_spec, simulated_run


@pytest.fixture(scope="module")
def one_sample(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(1), scene_spec("glossy_metal"))


@pytest.fixture(scope="module")
def few(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(6), scene_spec("glossy_metal"))


@pytest.mark.parametrize(
    ("name", "options"),
    [
        ("rgl", Options()),
        ("merl", Options()),
        ("factored", Options()),
        ("hdf5", Options(grid="hybrid")),
    ],
)
def test_a_run_of_fewer_samples_than_a_simplex_is_refused_in_every_grid_format(
    one_sample: Path, tmp_path: Path, name: str, options: Options
) -> None:
    with pytest.raises(GonioError) as caught:
        export(one_sample, name, tmp_path / f"out.{name}", options)
    assert str(caught.value) == (
        "the run has 1 calibrated sample: expected at least 4, one simplex of its 3 "
        "coordinates, before a grid is filled from them (measure more targets, or give "
        "--allow-sparse to export anyway)"
    )
    assert listing(tmp_path) == []


@pytest.mark.parametrize(
    ("name", "options", "says"),
    [
        ("rgl", Options(), "support 27.0% of the RGL pairs (4,459 of 16,512)"),
        ("merl", Options(), "support 39.1% of the MERL bins (428,985 of 1,096,216)"),
        ("factored", Options(), "support 37.4% of the factored table's bins (195,872 of 524,288)"),
    ],
)
def test_a_run_that_supports_almost_nothing_is_refused(
    few: Path, tmp_path: Path, name: str, options: Options, says: str
) -> None:
    with pytest.raises(GonioError) as caught:
        export(few, name, tmp_path / f"out.{name}", options)
    message = str(caught.value)
    assert says in message and f"expected at least {MIN_SUPPORTED:.0%}" in message
    assert "--allow-sparse" in message and "\n" not in message
    assert listing(tmp_path) == []


def test_allow_sparse_writes_it_with_a_warning_on_stderr(
    few: Path, tmp_path: Path, run_gonio: Callable[..., CliResult]
) -> None:
    out = tmp_path / "out.bsdf"
    result = run_gonio(
        "export", str(few), "--format", "rgl", "-o", str(out), "--allow-sparse", "-q"
    )
    assert result.returncode == 0 and out.stat().st_size > 0 and result.stdout == ""
    assert result.stderr.splitlines() == [
        "gonio: warning: the run's samples support 27.0% of the RGL pairs (4,459 of 16,512); "
        "the rest would be the reconstruction's extrapolation (below 40%; written as asked "
        "by --allow-sparse)"
    ]


def test_gonio_export_refuses_a_sparse_run_in_one_line(few: Path, tmp_path: Path) -> None:
    line = refused(
        tmp_path, "export", str(few), "--format", "rgl", "-o", str(tmp_path / "out.bsdf")
    )
    assert line.startswith("gonio: error: the run's samples support 27.0% of the RGL pairs")
    assert line.endswith(
        "expected at least 40% (measure more targets, or give --allow-sparse to export anyway)"
    )
