"""One combination → one row: every column, in order; a combination the planner
refuses is a row with the reason and no figures, not a crash of the sweep."""

from __future__ import annotations

from pathlib import Path

import pytest

from gonio.planner import adaptive
from gonio.tradeoff.grid import load_sweep
from gonio.tradeoff.runner import FIGURE_COLUMNS, run
from gonio.tradeoff.sweep import COLUMNS
from tests.gonio.tradeoff.conftest import SMALL, write_sweep


def test_a_refused_combination_is_a_row_with_the_reason(tmp_path: Path) -> None:
    """A combination the planner refuses (the sweep file refuses such counts itself, so the
    task is edited after loading, as a plan no sweep file can write)."""
    axes = {**SMALL["axes"], "parametrization": ["hybrid"], "sampling": ["sobol"], "samples": [100]}
    task = load_sweep(write_sweep(tmp_path, axes=axes)).tasks[0]
    task.plan["sampling"]["target"] = 2_000_000
    row = run(task)
    assert tuple(row) == COLUMNS
    assert "expected at most 1,000,000 targets" in row["error"] and "\n" not in row["error"]
    assert all(row[c] is None for c in FIGURE_COLUMNS if c != "error")
    assert row["wall_s"] is not None and row["wall_s"] >= 0
    assert {k: row[k] for k in task.inputs} == task.inputs


def test_an_adaptive_combination_counts_both_passes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)  # a faster density
    axes = {
        **SMALL["axes"],
        "parametrization": ["rusinkiewicz"],
        "sampling": ["adaptive"],
        "samples": [60],
        "method": ["linear"],
    }
    sweep = load_sweep(write_sweep(tmp_path, axes=axes, adaptive={"survey": 24, "model": "survey"}))
    (task,) = sweep.tasks
    assert task.plan["sampling"]["adaptive"]["model"] == "survey"
    row = run(task)
    assert row["error"] == ""
    assert row["targets"] == 60 and row["measured"] == 60
    assert row["log_rmse"] is not None and row["log_rmse"] > 0
