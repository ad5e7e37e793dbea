"""`gonio tradeoff` refuses a bad sweep file, output folder or option in one line with
exit code 2, before anything runs (a whole run is in tests/gonio/tradeoff)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.tradeoff.executors import CONNECT_TIMEOUT_S
from tests.conftest import CliResult
from tests.gonio.tradeoff.conftest import SMALL, write_sweep

GONIO = Path(sys.executable).with_name("gonio")


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (["--target-error", "0"], "--target-error: expected a positive number, got '0'"),
        (["--target-error", "nan"], "expected a positive number, got 'nan'"),
        (["-j", "0"], "--jobs: expected a whole number of processes (this machine has"),
        (["-j", "100000"], "got '100000'"),
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


def test_a_budget_beyond_a_day_is_refused_at_once_in_a_real_process(tmp_path: Path) -> None:
    sweep = write_sweep(tmp_path, axes={**SMALL["axes"], "minutes": [1_000_000]})
    r = subprocess.run(
        [str(GONIO), "tradeoff", str(sweep), "-o", str(tmp_path / "out"), "-q"],
        capture_output=True,
        text=True,
        timeout=120,
        stdin=subprocess.DEVNULL,
    )
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1 and f"{sweep}:" in r.stderr
    assert "axes.minutes.0: expected at most 1440" in r.stderr
    assert not (tmp_path / "out").exists()


def test_a_sweep_whose_every_combination_failed_exits_1_saying_so(tmp_path: Path) -> None:
    # 0.3 s: above one sample's time (0.25 s), below any plan's (a move to the target too)
    axes = {**SMALL["axes"], "parametrization": ["rusinkiewicz"], "minutes": [0.005]}
    sweep = write_sweep(tmp_path, axes=axes)
    r = subprocess.run(
        [str(GONIO), "tradeoff", str(sweep), "-o", str(tmp_path / "out"), "-q", "-j", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        stdin=subprocess.DEVNULL,
    )
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1, r.stderr
    assert r.stderr.startswith("gonio: all 2 combinations failed; the first: combination ")
    assert "no target of this plan fits 0.3 s of instrument time" in r.stderr
