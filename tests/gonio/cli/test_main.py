"""The `gonio` command: the console script and ``python -m gonio`` as real processes
(the installed entry point and the exit code), everything else in-process."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

import gonio
from gonio.cli import COMMANDS
from tests.conftest import CliResult

GONIO = Path(sys.executable).with_name("gonio")
Gonio = Callable[..., CliResult]


def test_the_console_script_runs_and_its_exit_code_is_the_command_s() -> None:
    ok = subprocess.run(
        [str(GONIO), "--version"], capture_output=True, text=True, timeout=60,
        stdin=subprocess.DEVNULL,
    )  # fmt: skip
    assert ok.returncode == 0
    assert ok.stdout.strip() == f"gonio {gonio.__version__}"
    bad = subprocess.run(
        [str(GONIO), "frobnicate"], capture_output=True, text=True, timeout=60,
        stdin=subprocess.DEVNULL,
    )  # fmt: skip
    assert bad.returncode == 2
    assert "Traceback" not in bad.stderr
    assert "invalid choice: 'frobnicate'" in bad.stderr


def test_python_dash_m_is_the_same_command() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "gonio", "--version"], capture_output=True, text=True, timeout=60
    )
    assert r.stdout.strip() == f"gonio {gonio.__version__}"


def test_help_lists_every_command_without_importing_them() -> None:
    """``gonio --help`` stays fast: no subcommand module (scipy, the simulator) loads."""
    code = (
        "import sys; from gonio.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = [m for m in ('scipy', 'numpy', 'gonio.cli.plan', 'gonio.cli.simulate', "
        "'gonio.cli.motors', 'gonio.cli.demo', 'sim') if m in sys.modules]\n"
        "print('HEAVY', heavy)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "usage: gonio" in r.stdout
    for name, (_, help_) in COMMANDS.items():
        assert name in r.stdout and help_[:30] in " ".join(r.stdout.split())
    assert r.stdout.strip().endswith("HEAVY []")


def test_no_command_prints_help(run_gonio: Gonio) -> None:
    r = run_gonio()
    assert r.returncode == 0
    assert "usage: gonio" in r.stdout


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_command_has_its_own_help(run_gonio: Gonio, name: str) -> None:
    r = run_gonio(name, "--help")
    assert r.returncode == 0
    assert f"usage: gonio {name}" in r.stdout


def test_demo_prints_the_tables(run_gonio: Gonio) -> None:
    r = run_gonio("demo")
    assert r.returncode == 0, r.stderr
    _, _, tables = r.stdout.partition("Parametrizations on named direction pairs")
    for name in ("spherical", "rusinkiewicz", "orthographic", "hybrid"):
        assert name in tables
    assert "opposite grazing" in tables
    assert "F_VOL" in tables
    # Every round-trip error printed is small: no configuration changes in the demo.
    errors = [float(line.split()[-1]) for line in tables.splitlines() if line.startswith("  ")][:36]
    assert len(errors) == 36
    assert max(errors) < 1e-7
