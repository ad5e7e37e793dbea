"""`gonio export --format csv`, read back with the standard library's csv module from
the layout docs/reference/formats.md describes (one header row of keys with unit suffixes)."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.analysis.calibrated import calibrate
from gonio.cli import main
from gonio.export.columns import Column
from gonio.export.csv import to_text
from gonio.store import open_run


@pytest.fixture(scope="module")
def table(run_file: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[str]]:
    out = tmp_path_factory.mktemp("csv") / "run.csv"
    assert main(["export", str(run_file), "--format", "csv", "-o", str(out), "-q"]) == 0
    with open(out, newline="", encoding="utf-8") as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], rows[1:]
    return {key: [row[j] for row in body] for j, key in enumerate(header)}


def _floats(cells: list[str]) -> np.ndarray:
    return np.array([math.nan if c == "" else float(c) for c in cells])


def test_one_row_per_sample_with_the_documented_columns(table, run_file):
    run = open_run(run_file)
    assert len(table["target"]) == len(run)
    documented = {"target", "wi_x", "wo_z", "theta_i_rad", "phi_o_rad", "exposure_s"}
    documented |= {"counts", "counts_std", "brdf_per_sr", "sigma_per_sr", "utc", "saturated"}
    documented |= {f"coord_{n}" for n in ("hbar", "k")} | {"coord_phi_k_minus_phi_h_rad"}
    documented |= {f"{a}_read_back_rad" for a in run.axes}
    documented |= {f"{a}_commanded_rad" for a in run.axes}
    assert documented <= set(table)


def test_values_are_the_runs_bit_for_bit(table, run_file):
    run = open_run(run_file)
    s = run.samples
    np.testing.assert_array_equal(np.array(table["target"], dtype=int), s["target"])
    for key in ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z", "counts", "exposure_s"):
        np.testing.assert_array_equal(_floats(table[key]), s[key])
    for axis in run.axes:
        np.testing.assert_array_equal(
            _floats(table[f"{axis}_read_back_rad"]), s[f"{axis}_read_back_rad"]
        )
    cal = calibrate(run)
    np.testing.assert_array_equal(_floats(table["brdf_per_sr"]), cal.brdf)
    np.testing.assert_array_equal(_floats(table["sigma_per_sr"]), cal.sigma)
    assert set(table["saturated"]) <= {"0", "1"}


def test_the_angles_are_those_of_the_directions(table):
    wi = np.stack([_floats(table[f"wi_{a}"]) for a in "xyz"], axis=1)
    theta = np.arccos(np.clip(wi[:, 2], -1, 1))
    phi = np.mod(np.arctan2(wi[:, 1], wi[:, 0]), 2 * np.pi)
    np.testing.assert_allclose(_floats(table["theta_i_rad"]), theta, atol=1e-12)
    np.testing.assert_allclose(_floats(table["phi_i_rad"]), phi, atol=1e-12)


def test_a_missing_value_is_an_empty_cell_and_booleans_are_0_1():
    columns = [
        Column("counts_std", "counts", "", np.array([1.5, np.nan])),
        Column("saturated", "", "", np.array([True, False])),
    ]
    rows = list(csv.reader(to_text(columns).splitlines()))
    assert rows == [["counts_std", "saturated"], ["1.5", "1"], ["", "0"]]


def test_a_run_file_that_is_not_one_is_one_line(tmp_path, capsys):
    bad = tmp_path / "x.sqlite"
    bad.write_bytes(b"not sqlite")
    assert main(["export", str(bad), "--format", "csv", "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "x.sqlite" in err
    assert not (tmp_path / "o.csv").exists()


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=20))
def test_floats_read_back_bit_for_bit(values):
    column = Column("x_s", "s", "", np.array(values, dtype=np.float64))
    rows = list(csv.reader(to_text([column]).splitlines()))
    back = _floats([row[0] for row in rows[1:]])
    original = np.array(values, dtype=np.float64)
    assert np.array_equal(np.isnan(back), np.isnan(original))
    finite = ~np.isnan(original)
    assert back[finite].tobytes() == original[finite].tobytes()  # −0.0 stays −0.0


def test_the_format_is_what_the_suffix_says_in_any_case(run_file, tmp_path, capsys):
    """``--format`` may be left out where ``-o``'s suffix says it, and is taken in any
    case; an unknown suffix without it is one line naming what would do."""
    plain = tmp_path / "plain.csv"
    assert main(["export", str(run_file), "--format", "csv", "-o", str(plain), "-q"]) == 0
    inferred = tmp_path / "RUN.CSV"
    assert main(["export", str(run_file), "-o", str(inferred), "-q"]) == 0
    upper = tmp_path / "upper.txt"
    assert main(["export", str(run_file), "--format", "CSV", "-o", str(upper), "-q"]) == 0
    assert inferred.read_bytes() == plain.read_bytes() == upper.read_bytes()
    capsys.readouterr()
    unknown = tmp_path / "run.dat"
    assert main(["export", str(run_file), "-o", str(unknown)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "give --format" in err and ".binary (merl)" in err
    assert main(["export", str(run_file), "--format", "velvet", "-o", str(unknown)]) == 2
    assert "--format velvet: unknown export format" in capsys.readouterr().err
    assert not unknown.exists()
