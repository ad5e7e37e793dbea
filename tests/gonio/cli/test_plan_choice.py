"""`gonio plan PLAN --budget-min M --material SPEC` as a user runs it: the candidates
table, the choice and why, the chosen plan stored with -o; a mistake is one line and
exit 2, before any planning."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import pytest

import gonio.tradeoff.choice as choice_module
from gonio.planner import read_plan
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]
QUICK = str(CONFIGS / "plans" / "quick.yaml")
GOLD = str(CONFIGS / "scenes" / "glossy_metal_fly.yaml")


def test_choice_on_glossy_gold(tmp_path: Path, run_gonio: Gonio) -> None:
    out_csv = tmp_path / "chosen.csv"
    r = run_gonio(
        "plan",
        QUICK,
        "--budget-min",
        "1.5",
        "--material",
        GOLD,
        "--test-pairs",
        "1000",
        "-o",
        str(out_csv),
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0] == (
        f"choice of plan for 1.5 min of instrument time, the material guess the material of {GOLD}"
    )
    assert lines[1].startswith("  predicted on 1000 test pairs (seed 14): ")
    assert lines[3].split() == [
        "candidate",
        "motion",
        "time",
        "samples",
        "log-RMSE",
        "method",
        "coverage",
        "gap",
    ]
    rows = {}
    for line in lines[4:11]:
        name, rest = line[2:36].strip(), line[36:].split()
        rows[name] = rest
    assert list(rows) == [
        "sobol, rusinkiewicz",
        "warped, rusinkiewicz",
        "detector arcs, 0.5°",
        "θh lines, 0.5°",
        "θh lines, 1°",
        "θh lines, 1°, 50 filled",
        "as written: sobol, hybrid",
    ]
    chosen = [name for name, rest in rows.items() if rest[-1] == "chosen"]
    assert len(chosen) == 1 and chosen[0].startswith("θh lines")
    errors = {name: float(rest[3]) for name, rest in rows.items()}
    assert errors[chosen[0]] == min(errors.values())
    for name, rest in rows.items():
        assert rest[0] == ("fly" if "°" in name else "stop")
        assert rest[4] in ("linear", "rbf")
        h, m, s = (int(x) for x in rest[1].split(":"))
        assert 75 <= 3600 * h + 60 * m + s <= 90
    best_stop = min(errors[n] for n in rows if "°" not in n)
    why = next(line for line in lines if line.startswith("chose "))
    match = re.fullmatch(
        r"chose (θh lines, [0-9.]+°) for 1.5 min: predicted log-RMSE ([0-9.]+) against ([0-9.]+) "
        r"for the best stop-and-go \(([^)]+)\), ([0-9.]+)× lower \(chosen in [0-9.]+ s\)",
        why,
    )
    assert match is not None, why
    assert match[1] == chosen[0]
    assert float(match[2]) == pytest.approx(errors[chosen[0]], rel=0.01)
    assert float(match[3]) == pytest.approx(best_stop, rel=0.01)
    # Then the chosen plan's summary, and the plan stored.
    assert "plan 'quick': isotropic rusinkiewicz, fly, rig 'arch-4axis'" in lines
    stored = read_plan(out_csv)
    assert stored.is_fly and stored.spec.sampling.fly_options().segment == "theta_h_line"
    assert f"wrote {len(stored)} targets to {out_csv}" in r.stdout
    assert stored.summary.total_s <= 90.0


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--budget-min", "1"], "--budget-min needs --material SPEC"),
        (["--material", GOLD], "--material applies with --budget-min M"),
        (["--test-pairs", "10"], "--test-pairs applies with --budget-min M"),
        (["--budget-min", "1", "--material", GOLD, "--bounds"], "--bounds applies to the plan"),
        (["--budget-min", "1", "--material", "scene"], "scene: expected a material guess"),
        (["--budget-min", "1", "--material", QUICK + ".x.yaml"], "cannot read it"),
        (["--budget-min", "1", "--material", "cook_torrance:alpha=-1"], "alpha"),
        (
            ["--budget-min", "1", "--material", GOLD, "--test-pairs", "1e12"],
            "--test-pairs: expected a whole number of pairs in [1, 1,000,000], got '1e12'",
        ),
    ],
    ids=[
        *("no-material", "no-budget", "pairs-alone", "bounds", "scene", "missing", "bad-model"),
        "pairs-beyond-memory",
    ],
)
def test_mistakes_are_one_line_before_any_planning(
    run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch, args: list[str], words: str
) -> None:
    def no_fitting(*args: object, **kwargs: object) -> None:
        raise AssertionError("fitted plans after a mistake")

    monkeypatch.setattr(choice_module, "fit", no_fitting)
    r = run_gonio("plan", QUICK, *args)
    assert r.returncode == 2, r.stderr
    assert r.stdout == ""
    assert r.stderr.startswith("gonio: error: ") and r.stderr.count("\n") == 1
    assert words in r.stderr


@pytest.mark.parametrize("value", ["0", "-1", "nan", "x", "1441"])
def test_a_bad_budget_is_a_usage_error(run_gonio: Gonio, value: str) -> None:
    r = run_gonio("plan", QUICK, "--budget-min", value, "--material", GOLD)
    assert r.returncode == 2
    assert r.stderr == (
        "gonio: error: plan: argument --budget-min: expected a positive number of minutes "
        f"of at most 1440, got {value!r} (see gonio plan --help)\n"
    )


def test_a_budget_nothing_fits(run_gonio: Gonio) -> None:
    r = run_gonio("plan", QUICK, "--budget-min", "0.005", "--material", GOLD)
    assert r.returncode == 2
    assert r.stderr.startswith("gonio: error: no candidate plan fits 0.3 s (sobol, rusinkiewicz: ")
    assert r.stderr.count("\n") == 1
