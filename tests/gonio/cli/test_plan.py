"""`gonio plan` as a user runs it: the summary table (with whether the ordering
converged, and the benchmark figures only with --bounds), the stored plan that reads
back, the coverage PNG, and a clear line when matplotlib is missing (checked before any
planning work)."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main
from gonio.config import ConfigError
from gonio.planner import load_plan_source, read_plan
from tests.conftest import CONFIGS

GONIO = Path(sys.executable).with_name("gonio")


def run(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(GONIO), *args], capture_output=True, text=True, timeout=300,
        stdin=subprocess.DEVNULL, env=env,
    )  # fmt: skip


def gonio_plan(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """`gonio plan ARGS` in this process: (exit code, stdout, stderr)."""
    code = main(["plan", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_quick_plan_end_to_end(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_csv, out_png = tmp_path / "plan.csv", tmp_path / "coverage.png"
    code, out, err = gonio_plan(
        capsys, str(CONFIGS / "plans" / "quick.yaml"), "-o", str(out_csv), "--plot", str(out_png)
    )
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == "plan 'quick': isotropic hybrid, sobol, rig 'arch-4axis'"
    counts = {
        " ".join(line.split()[:-1]): int(line.split()[-1])
        for line in lines[1:10]
        if line.strip() and line.split()[-1].isdigit()
    }
    assert counts["kept"] == 500
    refused = sum(v for k, v in counts.items() if k.startswith("refused:"))
    assert counts["requested"] == counts["outside the domain"] + refused + 500
    duration = next(line for line in lines if "predicted duration" in line).split()[2]
    h, m, s = (int(x) for x in duration.split(":"))
    assert 0 < h * 3600 + m * 60 + s < 24 * 3600
    assert f"wrote 500 targets to {out_csv}" in out
    # The stored plan reads back as the plan built here from the same files.
    stored = read_plan(out_csv)
    assert stored == dataclasses.replace(
        load_plan_source(CONFIGS / "plans" / "quick.yaml").build(), summary=stored.summary
    )
    assert np.all(np.diff(stored.arrival_s) > 0)
    # A real PNG of the figure's size.
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image

    image = matplotlib.image.imread(out_png)
    assert image.shape[0] >= 600 and image.shape[1] >= 1200
    assert image[..., :3].std() > 0.05  # not blank


def test_convergence_is_printed(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = gonio_plan(capsys, str(CONFIGS / "plans" / "quick.yaml"))
    assert code == 0
    line = next(x for x in out.splitlines() if x.startswith("  ordering  "))
    words = line.split()
    assert words[1:3] == ["converged", "after"] and words[4:] == ["moves", "(budget", "5,100)"]
    assert 0 < int(words[3].replace(",", "")) < 5100
    assert "ordering took" in out


def test_a_binding_move_budget_is_printed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (CONFIGS / "plans" / "quick.yaml").read_text(encoding="utf-8")
    plan = tmp_path / "tight.yaml"
    plan.write_text(
        text.replace("../rigs/arch.yaml", str(CONFIGS / "rigs" / "arch.yaml")) + "max_moves: 7\n",
        encoding="utf-8",
    )
    code, out, _ = gonio_plan(capsys, str(plan), "-o", str(tmp_path / "p.csv"))
    assert code == 0
    assert (
        "  ordering                  stopped at the move budget (7 moves): not converged\n" in out
    )
    s = read_plan(tmp_path / "p.csv").summary
    assert s.stopped == "move budget" and not s.converged and s.moves == 7


def test_bounds_only_with_the_option(capsys: pytest.CaptureFixture[str]) -> None:
    quick = str(CONFIGS / "plans" / "quick.yaml")
    _, plain, _ = gonio_plan(capsys, quick)
    code, bounds, _ = gonio_plan(capsys, quick, "--bounds")
    assert code == 0
    for label in ("in generation order", "lower bound (MST)"):
        assert label not in plain
        assert label in bounds
    generation = next(x for x in bounds.splitlines() if "in generation order" in x)
    assert generation.endswith("× the ordered plan)")
    assert float(generation.split("(")[1].split("×")[0]) >= 2.0
    mst = next(x for x in bounds.splitlines() if "lower bound (MST)" in x)
    assert float(mst.split("= ")[1].split("×")[0]) <= 1.3
    # Everything else is the same table.
    kept = [x for x in bounds.splitlines() if x not in (generation, mst)]
    without_took = [x for x in kept if "ordering took" not in x]
    assert without_took == [x for x in plain.splitlines() if "ordering took" not in x]


def test_anisotropic_plan_with_the_other_rig(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = gonio_plan(
        capsys, str(CONFIGS / "plans" / "quick.yaml"),
        "--rig", str(CONFIGS / "rigs" / "in_plane.yaml"), "--plot", str(tmp_path / "c.png"),
        "-o", str(tmp_path / "p.csv"),
    )  # fmt: skip
    assert code == 0, err
    assert "rig 'in-plane-4axis'" in out
    assert (tmp_path / "c.png").stat().st_size > 10_000
    assert read_plan(tmp_path / "p.csv").rig.spec.name == "in-plane-4axis"
    # Read against the arch rig (the plan file's own rig field): refused by hash.
    with pytest.raises(ConfigError, match="built for rig 'in-plane-4axis'"):
        read_plan(tmp_path / "p.csv", rig=CONFIGS / "rigs" / "arch.yaml")


def test_missing_matplotlib_is_one_line_before_any_work(tmp_path: Path) -> None:
    """A matplotlib that cannot be imported (shadowed on PYTHONPATH) gives one line
    saying how to install the plot extra, and no plan is written."""
    shadow = tmp_path / "shadow" / "matplotlib"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('no matplotlib here')\n")
    env = {**os.environ, "PYTHONPATH": str(shadow.parent)}
    out_csv = tmp_path / "plan.csv"
    r = run(
        "plan", str(CONFIGS / "plans" / "quick.yaml"), "-o", str(out_csv),
        "--plot", str(tmp_path / "c.png"), env=env,
    )  # fmt: skip
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == (
        "gonio: error: plotting needs matplotlib: pip install 'gonio[plot]' "
        "(or pip install matplotlib)\n"
    )
    assert not out_csv.exists()


@pytest.mark.parametrize("args", [["plan"], ["plan", "a.yaml", "--frobnicate"]])
def test_usage_errors(args: list[str]) -> None:
    r = run(*args)
    assert r.returncode == 2
    assert "usage: gonio" in r.stderr
    assert "Traceback" not in r.stderr
