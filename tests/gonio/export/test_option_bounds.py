"""Every numeric export option is bounded by what it means, checked before any work and
before any output exists: the factored format's terms by the rank of the tables they
factor, the HDF5 grid's points by the memory its evaluation would need."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.errors import GonioError
from gonio.export import MAX_INNER, MAX_OUTER, Options, check_options, export
from tests.conftest import CliResult
from tests.support.process import listing, refused


@pytest.mark.parametrize(
    ("name", "options", "says"),
    [
        ("factored", Options(outer=100_000), f"expected 1 to {MAX_OUTER} outer terms"),
        ("factored", Options(outer=0), f"expected 1 to {MAX_OUTER} outer terms"),
        ("factored", Options(inner=MAX_INNER + 1), f"1 to {MAX_INNER} inner terms"),
        ("hdf5", Options(grid="hybrid", grid_points=100_000), "of memory to evaluate"),
        ("hdf5", Options(grid="hybrid", grid_points=1), "expected at least 2"),
    ],
)
def test_an_option_beyond_its_meaning_is_refused_before_the_output_exists(
    run_file: Path, tmp_path: Path, name: str, options: Options, says: str
) -> None:
    with pytest.raises(GonioError, match=says):
        check_options(name, options)
    with pytest.raises(GonioError, match=says):
        export(run_file, name, tmp_path / "out", options)
    assert listing(tmp_path) == []


def test_the_grid_message_says_what_it_needs_and_what_there_is() -> None:
    with pytest.raises(GonioError) as caught:
        check_options("hdf5", Options(grid="hybrid", grid_points=100_000))
    assert str(caught.value).startswith(
        "--grid-points 100000: a 3-dimensional grid of 100000^3 nodes needs about 165 PiB "
        "of memory to evaluate; this machine has "
    )
    check_options("hdf5", Options(grid="hybrid", grid_points=32))  # the default fits
    check_options("factored", Options(outer=MAX_OUTER, inner=MAX_INNER))


def test_gonio_export_refuses_in_one_line_and_writes_nothing(
    run_file: Path, tmp_path: Path
) -> None:
    out = tmp_path / "out.txt"
    line = refused(
        tmp_path,
        "export",
        str(run_file),
        "--format",
        "factored",
        "-o",
        str(out),
        "--outer",
        "100000",
    )
    assert line == (
        "gonio: error: export: argument --outer: expected a whole number of outer terms in "
        f"[1, {MAX_OUTER}], got '100000' (see gonio export --help)"
    )


def test_in_process_hdf5_grid_refusal(
    run_file: Path, tmp_path: Path, run_gonio: Callable[..., CliResult]
) -> None:
    result = run_gonio("export", str(run_file), "--format", "hdf5", "--grid", "hybrid",
                       "--grid-points", "5000", "-o", str(tmp_path / "out.h5"))  # fmt: skip
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1
    assert "needs about 21.1 TiB of memory" in result.stderr and listing(tmp_path) == []
    result = run_gonio("export", str(run_file), "--format", "hdf5", "--grid", "hybrid",
                       "--grid-points", "100000", "-o", str(tmp_path / "out.h5"))  # fmt: skip
    assert result.returncode == 2 and "points in [1, 10,000], got '100000'" in result.stderr
