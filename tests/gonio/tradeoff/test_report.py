"""report.md from rows of known figures: the front, the best of each parametrization,
the target line (met or not), the failures counted by reason; and the figures, drawn
from the same rows (and from rows where nothing was scored)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib import image

from gonio.tradeoff.grid import Sweep, load_sweep
from gonio.tradeoff.plots import plot_scene
from gonio.tradeoff.report import render
from gonio.tradeoff.runner import FIGURE_COLUMNS
from tests.gonio.tradeoff.conftest import write_sweep

#: (instrument s, log-RMSE) of the four combinations of SMALL, in grid order: hybrid
#: sobol, hybrid warped, rusinkiewicz sobol, rusinkiewicz warped (the last fails).
FIGURES = [(100.0, 0.04), (120.0, 0.02), (90.0, 0.05), (None, None)]


@pytest.fixture(scope="module")
def sweep(tmp_path_factory: pytest.TempPathFactory) -> Sweep:
    return load_sweep(write_sweep(tmp_path_factory.mktemp("report")))


def known_rows(sweep: Sweep) -> list[dict[str, Any]]:
    out = []
    for task, (t, e) in zip(sweep.tasks, FIGURES, strict=True):
        row = {**task.inputs, **dict.fromkeys(FIGURE_COLUMNS), "error": ""}
        if t is None:
            row["error"] = "the rig reaches nothing"
        else:
            row.update(instrument_s=t, predicted_s=t - 5, log_rmse=e, measured=100)
        out.append(row)
    return out


def ids_in(section: str) -> list[str]:
    return [line.split("`")[1] for line in section.splitlines() if line.count("`") == 2]


def test_the_report_tables(sweep: Sweep) -> None:
    rows = known_rows(sweep)
    ids = [r["id"] for r in rows]
    text = render(sweep, rows, target=0.03)
    front = text.split("Pareto front")[1].split("Best of each")[0]
    assert ids_in(front) == [ids[2], ids[0], ids[1]]
    per = text.split("Best of each parametrization")[1].split("Fastest")[0]
    assert ids_in(per) == [ids[1], ids[2]]
    assert f"Fastest meeting log_rmse ≤ 0.03: `{ids[1]}`, 0.02 in 120.0 s (hybrid, warped" in text
    assert "4 of 4 combinations finished (1 failed)" in text
    assert "| 1 | the rig reaches nothing |" in text
    assert "Constant over the sweep: samples 100," in text
    missed = render(sweep, rows, target=0.01)
    assert "No combination meets log_rmse ≤ 0.01: the best reaches 0.02." in missed
    assert "No combination of this scene has finished." in render(sweep, [], target=None)


def test_the_figures_are_drawn_from_the_rows(sweep: Sweep, tmp_path: Path) -> None:
    scored = plot_scene(tmp_path, "matte", known_rows(sweep), "log_rmse")
    assert [p.name for p in scored] == ["matte-error-vs-time.png", "matte-error-vs-samples.png"]
    empty = plot_scene(tmp_path, "none scored", known_rows(sweep)[3:], "log_rmse")
    assert [p.name for p in empty] == [
        "none-scored-error-vs-time.png",
        "none-scored-error-vs-samples.png",
    ]

    def coloured(path: Path) -> int:
        """Pixels of a strong colour (the points; axes and text are grey)."""
        pixels = image.imread(path)
        assert pixels.shape[:2] == (480, 700)
        return int(np.count_nonzero(np.ptp(pixels[..., :3], axis=-1) > 0.3))

    assert all(coloured(p) > 50 for p in scored)
    assert all(coloured(p) < 10 for p in empty)
