"""The `gonio` command: the console script and ``python -m gonio`` as real processes
(the installed entry point and the exit code), everything else in-process."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

import gonio
from gonio.cli import COMMANDS
from tests.conftest import CliResult

#: The repository (the commands run from it, as in the docs).
ROOT = Path(__file__).resolve().parents[3]

GONIO = Path(sys.executable).with_name("gonio")
Gonio = Callable[..., CliResult]


def test_the_console_script_runs_and_its_exit_code_is_the_command_s() -> None:
    ok = subprocess.run(
        [str(GONIO), "--version"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert ok.returncode == 0
    assert ok.stdout.strip() == f"gonio {gonio.__version__}"
    bad = subprocess.run(
        [str(GONIO), "frobnicate"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
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
        "'gonio.cli.motors', 'gonio.cli.tables', 'sim') if m in sys.modules]\n"
        "print('HEAVY', heavy)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "usage: gonio" in r.stdout
    for name, (_, help_) in COMMANDS.items():
        assert name in r.stdout and help_[:30] in " ".join(r.stdout.split())
    assert r.stdout.strip().endswith("HEAVY []")


#: What a command's help, or a plan file it cannot read, never needs: the planner's and
#: the models' scipy, the compiled search (numba), figures, the web server, Dask, the
#: simulator.
NOT_FOR_HELP = (
    "scipy.special",
    "scipy.stats",
    "scipy.optimize",
    "scipy.spatial",
    "scipy.interpolate",
    "numba",
    "matplotlib",
    "h5py",
    "starlette",
    "dask",
    "sim",
)
#: The commands whose help loads none of `NOT_FOR_HELP`.
LIGHT = ("plan", "acquire", "serve", "tradeoff", "align", "info", "fit", "motors", "detector")


def test_the_light_commands_help_loads_no_heavy_module(tmp_path: Path) -> None:
    """One interpreter runs each light command's help, then ``gonio plan`` on a missing
    file; none of them loads scipy's heavy parts, numba, matplotlib, the web server, Dask
    or the simulator (a regression costs each process the suite starts a second or two
    of imports)."""
    runs = [[name, "--help"] for name in LIGHT] + [["plan", str(tmp_path / "missing.yaml")]]
    code = (
        "import contextlib, io, json, sys\n"
        "from gonio.cli import main\n"
        "codes = []\n"
        "for argv in json.loads(sys.argv[1]):\n"
        "    out = io.StringIO()\n"
        "    try:\n"
        "        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):\n"
        "            codes.append(main(argv))\n"
        "    except SystemExit as exc:\n"
        "        codes.append(exc.code)\n"
        "heavy = sorted(m for m in json.loads(sys.argv[2]) if m in sys.modules)\n"
        "print(json.dumps({'codes': codes, 'heavy': heavy}))\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", code, json.dumps(runs), json.dumps(NOT_FOR_HELP)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert r.returncode == 0, r.stderr
    found = json.loads(r.stdout.splitlines()[-1])
    assert found["codes"] == [0] * len(LIGHT) + [2], found
    assert found["heavy"] == [], found


def test_no_command_prints_help(run_gonio: Gonio) -> None:
    r = run_gonio()
    assert r.returncode == 0
    assert "usage: gonio" in r.stdout


@pytest.mark.parametrize("name", list(COMMANDS))
def test_each_command_has_its_own_help(run_gonio: Gonio, name: str) -> None:
    r = run_gonio(name, "--help")
    assert r.returncode == 0
    assert f"usage: gonio {name}" in r.stdout


def test_tables_prints_the_tables(run_gonio: Gonio) -> None:
    r = run_gonio("tables")
    assert r.returncode == 0, r.stderr
    _, _, tables = r.stdout.partition("Parametrizations on named direction pairs")
    for name in ("spherical", "rusinkiewicz", "orthographic", "hybrid"):
        assert name in tables
    assert "opposite grazing" in tables
    assert "F_VOL" in tables
    # Every round-trip error printed is small: no configuration changes in the tables.
    errors = [float(line.split()[-1]) for line in tables.splitlines() if line.startswith("  ")][:36]
    assert len(errors) == 36
    assert max(errors) < 1e-7


@pytest.mark.parametrize(
    "args",
    [["plan", "configs/plans/rehearsal.yaml"], ["--help"]],  # 30 targets: quick to plan
    ids=["plan", "help"],
)
def test_a_closed_pipe_ends_quietly(args: list[str]) -> None:
    """`gonio plan … | head -1` with the reader gone before the first line: no
    BrokenPipeError traceback and no "Exception ignored" at exit, exit code 141 (or 0)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "gonio", *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader is gone before anything was written
    with proc.stderr:
        err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) in (0, 141), err
    assert err == ""


def test_a_closed_pipe_in_a_real_shell_pipeline() -> None:
    """The same through ``| head -1``: the first line arrives, the rest is dropped."""
    r = subprocess.run(
        ["sh", "-c", f"'{sys.executable}' -m gonio tables | head -1; exit $(( 0 ))"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert r.stdout.startswith("Parametrizations on named direction pairs")
    assert len(r.stdout.splitlines()) == 1
    assert r.stderr == ""


def test_a_closed_pipe_in_process_returns_141(
    monkeypatch: pytest.MonkeyPatch, run_gonio: Gonio
) -> None:
    """Output printed by any subcommand: the error surfaces in `main`, which ends quietly."""
    from gonio.cli import tables

    def closed(*args: object, **kwargs: object) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(tables, "print", closed, raising=False)
    r = run_gonio("tables")
    assert r.returncode == 141
    assert r.stderr == ""


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (["plan"], "plan: the following arguments are required: plan (see gonio plan --help)"),
        (
            ["plan", "a.yaml", "--frobnicate"],
            "plan: unrecognized arguments: --frobnicate (see gonio plan --help)",
        ),
        (["motors"], "motors: the following arguments are required: ACTION"),
        (
            ["motors", "status", "--ids", "x"],
            "motors status: argument --ids: expected IDs like 1,2,5-7, got 'x' "
            "(see gonio motors status --help)",
        ),
        (["frobnicate"], "argument COMMAND: invalid choice: 'frobnicate'"),
        (
            ["simulate", "p.yaml", "--seed", "two"],
            "simulate: argument --seed: expected a whole number ≥ 0 below 2**63, got 'two'",
        ),
    ],
    ids=["missing", "unknown-option", "missing-action", "bad-type", "bad-command", "bad-int"],
)
def test_usage_errors_are_one_line(run_gonio: Gonio, args: list[str], line: str) -> None:
    r = run_gonio(*args)
    assert r.returncode == 2
    assert r.stdout == ""
    assert len(r.stderr.splitlines()) == 1, r.stderr
    assert r.stderr.startswith(f"gonio: error: {line}")


def test_a_path_the_kernel_refuses_is_one_line(run_gonio: Gonio, tmp_path: Path) -> None:
    """A name longer than the filesystem allows, as a plan's rig or as -o: one line
    naming the path, exit 2 (it was an OSError traceback)."""
    long_name = "r" * 300
    plan = tmp_path / "plan.yaml"
    plan.write_text(f"name: p\nrig: {long_name}.yaml\nsampling: {{strategy: sobol, target: 10}}\n")
    r = run_gonio("plan", str(plan))
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    # The path is shown cut in the middle (gonio.config.yaml_files.shown_path), its end kept.
    assert "rrr.yaml: cannot read the file: File name too long" in r.stderr
    assert len(r.stderr) < 600
    quickstart = ROOT / "configs" / "plans" / "quickstart.yaml"
    scene = quickstart.parents[1] / "scenes" / "matte.yaml"
    r = run_gonio(
        "acquire",
        str(quickstart),
        "--scene",
        str(scene),
        "-o",
        str(tmp_path / f"{long_name}.sqlite"),
    )
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "File name too long" in r.stderr


@pytest.mark.parametrize(
    "args",
    [["schema", "plan"], ["plan", "configs/plans/rehearsal.yaml"], ["tables"], ["--help"]],
    ids=["schema", "plan", "tables", "help"],
)
def test_a_full_standard_output_is_one_line_and_exit_74(args: list[str]) -> None:
    """``gonio … > /dev/full``: one line on stderr naming the standard output, exit 74
    (sysexits' EX_IOERR), no traceback and no "Exception ignored" at exit."""
    with open("/dev/full", "w") as full:
        r = subprocess.run(
            [sys.executable, "-m", "gonio", *args],
            cwd=ROOT,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=60,
            stdin=subprocess.DEVNULL,
        )
    assert r.returncode == 74, r.stderr
    assert r.stderr == "gonio: error: cannot write the standard output: No space left on device\n"


def test_a_closed_standard_output_is_one_line_and_exit_74() -> None:
    r = subprocess.run(
        ["sh", "-c", f"'{sys.executable}' -m gonio schema plan >&-"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert r.returncode == 74, r.stderr
    assert r.stderr == "gonio: error: the standard output is closed\n"
