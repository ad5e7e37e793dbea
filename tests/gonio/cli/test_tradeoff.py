"""`gonio tradeoff` refuses a bad sweep file, output folder or option in one line with
exit code 2, before anything runs (a whole run is in tests/gonio/tradeoff)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.tradeoff.executors import CONNECT_TIMEOUT_S
from tests.conftest import CliResult
from tests.gonio.tradeoff.conftest import write_sweep


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (["--target-error", "0"], "--target-error: expected a positive number, got '0'"),
        (["--target-error", "nan"], "expected a positive number, got 'nan'"),
        (["-j", "0"], "--jobs: expected a positive whole number, got '0'"),
    ],
)
def test_a_bad_option_is_a_usage_error(
    tmp_path: Path, run_gonio: Callable[..., CliResult], options: list[str], expected: str
) -> None:
    sweep = write_sweep(tmp_path)
    result = run_gonio("tradeoff", str(sweep), "-o", str(tmp_path / "out"), *options)
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert expected in result.stderr and not (tmp_path / "out").exists()


def test_a_bad_sweep_or_folder_is_one_line(
    tmp_path: Path, run_gonio: Callable[..., CliResult]
) -> None:
    bad = write_sweep(tmp_path, "bad", metric="rmse")
    result = run_gonio("tradeoff", str(bad), "-o", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert f"{bad}:" in result.stderr and "metric: unknown metric 'rmse'" in result.stderr
    (tmp_path / "file").write_text("")
    result = run_gonio("tradeoff", str(write_sweep(tmp_path)), "-o", str(tmp_path / "file"))
    assert result.returncode == 2 and "is a file; expected an output folder" in result.stderr
    result = run_gonio("tradeoff", str(tmp_path / "none.yaml"), "-o", str(tmp_path / "out"))
    assert result.returncode == 2 and "none.yaml: cannot read the file" in result.stderr


@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("tcp://256.1.1.1:99999", "port 99999: expected 1…65535"),
        ("tcp://256.1.1.1:8786", "256.1.1.1 is not an IP address"),
        ("tcp://[::1::2]:8786", "is not an IP address"),
        ("tcp://scheduler:0", "port 0: expected 1…65535"),
        ("scheduler", "expected an address tcp://HOST:PORT"),
    ],
)
def test_a_scheduler_address_that_cannot_be_one_is_refused_before_anything_runs(
    tmp_path: Path, run_gonio: Callable[..., CliResult], address: str, expected: str
) -> None:
    sweep = write_sweep(tmp_path)
    result = run_gonio("tradeoff", str(sweep), "-o", str(tmp_path / "out"), "--scheduler", address)
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert expected in result.stderr and result.stdout == ""
    assert not (tmp_path / "out").exists()


def test_the_help_states_the_connect_timeout_the_code_waits(
    run_gonio: Callable[..., CliResult],
) -> None:
    help_text = " ".join(run_gonio("tradeoff", "--help").stdout.split())
    assert f"answer within {CONNECT_TIMEOUT_S:g} s" in help_text


def test_a_sample_count_no_plan_may_keep_is_refused_before_anything_runs(
    tmp_path: Path, run_gonio: Callable[..., CliResult]
) -> None:
    axes = {"parametrization": ["hybrid"], "sampling": ["sobol"], "samples": [100, 10**9]}
    sweep = write_sweep(tmp_path, axes=axes)
    result = run_gonio("tradeoff", str(sweep), "-o", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert "axes.samples.1: expected at most 1,000,000 targets" in result.stderr
    assert not (tmp_path / "out").exists()
