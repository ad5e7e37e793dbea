"""The `gonio` console script, run as a real subprocess (the installed entry point)."""

import subprocess
import sys
from pathlib import Path

import gonio

GONIO = Path(sys.executable).with_name("gonio")


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(GONIO), *args], capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL
    )


def test_version() -> None:
    r = run("--version")
    assert r.returncode == 0
    assert r.stdout.strip() == f"gonio {gonio.__version__}"


def test_help_lists_the_commands() -> None:
    r = run("--help")
    assert r.returncode == 0
    assert "demo" in r.stdout
    assert "usage: gonio" in r.stdout


def test_no_command_prints_help() -> None:
    r = run()
    assert r.returncode == 0
    assert "usage: gonio" in r.stdout


def test_unknown_command_is_a_usage_error_without_traceback() -> None:
    r = run("frobnicate")
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "invalid choice: 'frobnicate'" in r.stderr


def test_demo_runs_the_simulated_job_and_prints_the_tables() -> None:
    r = run("demo")
    assert r.returncode == 0, r.stderr
    job, _, tables = r.stdout.partition("Parametrizations on named direction pairs")
    # The main job: the quick plan measured on the simulated rig, calibrated, checked.
    assert "plan 'quick': isotropic hybrid, sobol, rig 'arch-4axis'" in job
    assert "simulated plan 'quick' on rig 'arch-4axis', scene 'matte'" in job
    targets = next(line for line in job.splitlines() if line.strip().startswith("targets"))
    assert targets.split()[-1] == "500"
    error = next(line for line in job.splitlines() if "recovered BRDF error" in line)
    assert float(error.split()[3].rstrip("%")) < 1.0  # median error with sensor noise, %
    for name in ("spherical", "rusinkiewicz", "orthographic", "hybrid"):
        assert name in tables
    assert "opposite grazing" in tables
    assert "F_VOL" in tables
    # Every round-trip error printed is small: no configuration changes in the demo.
    errors = [float(line.split()[-1]) for line in tables.splitlines() if line.startswith("  ")][:36]
    assert len(errors) == 36
    assert max(errors) < 1e-7


def test_python_dash_m_is_the_same_command() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "gonio", "--version"], capture_output=True, text=True, timeout=60
    )
    assert r.stdout.strip() == f"gonio {gonio.__version__}"
