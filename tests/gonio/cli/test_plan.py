"""`gonio plan` as a user runs it (in-process, through `gonio.cli.main`): the summary
table (with whether the ordering converged, and the benchmark figures only with
--bounds), the stored plan that reads back, the coverage PNG, and a clear line when
matplotlib is missing (checked before any planning work)."""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import gonio.cli.plan as plan_command
from gonio.config import ConfigError
from gonio.planner import Plan, read_plan
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]
QUICK = str(CONFIGS / "plans" / "quick.yaml")


def gonio_plan(run_gonio: Gonio, *args: str) -> tuple[int, str, str]:
    """`gonio plan ARGS`: (exit code, stdout, stderr)."""
    r = run_gonio("plan", *args)
    return r.returncode, r.stdout, r.stderr


def test_quick_plan_end_to_end(tmp_path: Path, run_gonio: Gonio, quick_plan: Plan) -> None:
    out_csv, out_png = tmp_path / "plan.csv", tmp_path / "coverage.png"
    code, out, err = gonio_plan(run_gonio, QUICK, "-o", str(out_csv), "--plot", str(out_png))
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
    assert stored == dataclasses.replace(quick_plan, summary=stored.summary)
    assert np.all(np.diff(stored.arrival_s) > 0)
    # A real PNG of the figure's size.
    assert out_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import matplotlib.image

    image = matplotlib.image.imread(out_png)
    assert image.shape[0] >= 600 and image.shape[1] >= 1200
    assert image[..., :3].std() > 0.05  # not blank


def test_convergence_is_printed(run_gonio: Gonio) -> None:
    code, out, _ = gonio_plan(run_gonio, QUICK)
    assert code == 0
    line = next(x for x in out.splitlines() if x.startswith("  ordering  "))
    words = line.split()
    assert words[1:3] == ["converged", "after"] and words[4:7] == ["moves,", "then", "500"]
    assert words[7:] == ["kicks", words[8], "kept);", "budgets", "5,100", "and", "500"]
    assert 0 < int(words[3].replace(",", "")) < 5100
    assert "ordering took" in out


def test_a_binding_move_budget_is_printed(tmp_path: Path, run_gonio: Gonio) -> None:
    text = (CONFIGS / "plans" / "quick.yaml").read_text(encoding="utf-8")
    plan = tmp_path / "tight.yaml"
    plan.write_text(
        text.replace("../rigs/arch.yaml", str(CONFIGS / "rigs" / "arch.yaml")) + "max_moves: 7\n",
        encoding="utf-8",
    )
    code, out, _ = gonio_plan(run_gonio, str(plan), "-o", str(tmp_path / "p.csv"))
    assert code == 0
    assert (
        "  ordering                  stopped at the move budget (7 moves): not converged\n" in out
    )
    s = read_plan(tmp_path / "p.csv").summary
    assert s.stopped == "move budget" and not s.converged and s.moves == 7


def test_bounds_only_with_the_option(run_gonio: Gonio) -> None:
    _, plain, _ = gonio_plan(run_gonio, QUICK)
    code, bounds, _ = gonio_plan(run_gonio, QUICK, "--bounds")
    assert code == 0
    for label in ("in generation order", "lower bound (Held–Karp)", "lower bound (MST)"):
        assert label not in plain
        assert label in bounds
    generation = next(x for x in bounds.splitlines() if "in generation order" in x)
    assert generation.endswith("× the ordered plan)")
    assert float(generation.split("(")[1].split("×")[0]) >= 2.0
    held_karp = next(x for x in bounds.splitlines() if "lower bound (Held–Karp)" in x)
    assert 1.0 <= float(held_karp.split("= ")[1].split()[0]) <= 1.02
    mst = next(x for x in bounds.splitlines() if "lower bound (MST)" in x)
    assert 1.0 <= float(mst.split("= ")[1].split()[0]) <= 1.3
    # Everything else is the same table.
    kept = [x for x in bounds.splitlines() if x not in (generation, held_karp, mst)]
    without_took = [x for x in kept if "ordering took" not in x]
    assert without_took == [x for x in plain.splitlines() if "ordering took" not in x]


def test_anisotropic_plan_with_the_other_rig(tmp_path: Path, run_gonio: Gonio) -> None:
    code, out, err = gonio_plan(
        run_gonio,
        QUICK,
        "--rig",
        str(CONFIGS / "rigs" / "in_plane.yaml"),
        "--plot",
        str(tmp_path / "c.png"),
        "-o",
        str(tmp_path / "p.csv"),
    )
    assert code == 0, err
    assert "rig 'in-plane-4axis'" in out
    assert (tmp_path / "c.png").stat().st_size > 10_000
    assert read_plan(tmp_path / "p.csv").rig.spec.name == "in-plane-4axis"
    # Read against the arch rig (the plan file's own rig field): refused by hash.
    with pytest.raises(ConfigError, match="built for rig 'in-plane-4axis'"):
        read_plan(tmp_path / "p.csv", rig=CONFIGS / "rigs" / "arch.yaml")


def test_missing_matplotlib_is_one_line_before_any_work(
    tmp_path: Path, run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A matplotlib that cannot be imported gives one line saying how to install the
    plot extra, before the plan is even read: nothing is planned, no plan is written."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # `import matplotlib` fails

    def no_planning(*args: object) -> None:
        raise AssertionError("planning started before matplotlib was checked")

    monkeypatch.setattr(plan_command, "load_plan_source", no_planning)
    out_csv = tmp_path / "plan.csv"
    r = run_gonio("plan", QUICK, "-o", str(out_csv), "--plot", str(tmp_path / "c.png"))
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == (
        "gonio: error: plotting needs matplotlib: pip install 'gonio[plot]' "
        "(or pip install matplotlib)\n"
    )
    assert not out_csv.exists()


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["plan"], "the following arguments are required: plan"),
        (["plan", "a.yaml", "--frobnicate"], "unrecognized arguments: --frobnicate"),
    ],
    ids=["no-plan-file", "unknown-option"],
)
def test_usage_errors(run_gonio: Gonio, args: list[str], words: str) -> None:
    r = run_gonio(*args)
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr == f"gonio: error: plan: {words} (see gonio plan --help)\n"
