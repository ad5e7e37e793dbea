"""A whole sweep: run the combinations its output folder does not hold yet (each row
stored as it finishes), then write what is read from the rows: ``results.csv``, the
figures, the target plans and ``report.md``."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gonio.progress import Progress
from gonio.tradeoff import executors
from gonio.tradeoff.front import fastest_meeting
from gonio.tradeoff.grid import INPUT_COLUMNS, Sweep
from gonio.tradeoff.plots import plot_scene
from gonio.tradeoff.report import render, write_report
from gonio.tradeoff.runner import FIGURE_COLUMNS, WALL_COLUMNS
from gonio.tradeoff.store import open_store, write_csv
from gonio.tradeoff.target import remove_target_plan, write_target_plan

#: The columns of results.csv, in order.
COLUMNS = (*INPUT_COLUMNS, *FIGURE_COLUMNS, *WALL_COLUMNS)


@dataclass(frozen=True)
class SweepResult:
    """What a sweep did: combinations run now and reused, the wall time of running
    them, the rows (grid order) and the files written."""

    ran: int
    reused: int
    wall_s: float
    rows: list[dict[str, Any]]
    files: list[Path]
    plans: dict[str, Path]


def run_sweep(
    sweep: Sweep,
    folder: Path,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    target: float | None = None,
    progress: Progress | None = None,
) -> SweepResult:
    """Run ``sweep`` into ``folder`` (see the module docstring): in this process for one
    job, else on ``jobs`` local processes, or on the Dask cluster at ``scheduler``."""
    with open_store(folder) as store:
        todo = [t for t in sweep.tasks if t.id not in store.rows]
        reused = len(sweep.tasks) - len(todo)
        if progress is not None:
            progress.start(len(todo), "combinations", unit="comb")

        def done(row: dict[str, Any]) -> None:
            store.append(row)
            if progress is not None:
                progress.advance()

        started = time.perf_counter()
        try:
            if scheduler is not None:
                executors.run_dask(todo, scheduler, done)
            elif jobs <= 1 or len(todo) <= 1:
                executors.run_here(todo, done)
            else:
                executors.run_local(todo, min(jobs, len(todo)), done)
        finally:
            if progress is not None:
                progress.close()
        wall = time.perf_counter() - started
        rows = [store.rows[t.id] for t in sweep.tasks if t.id in store.rows]
        files, plans = write_outputs(sweep, folder, rows, target)
    return SweepResult(len(todo), reused, wall, rows, files, plans)


def write_outputs(
    sweep: Sweep, folder: Path, rows: Sequence[dict[str, Any]], target: float | None
) -> tuple[list[Path], dict[str, Path]]:
    """results.csv, each scene's figures and target plan, and report.md (last: it names
    the others); (the files written, the target plan of each scene that has one)."""
    metric = sweep.spec.metric
    files = [write_csv(folder, rows, COLUMNS)]
    plans: dict[str, Path] = {}
    for scene in sweep.scenes:
        mine = [r for r in rows if r["scene"] == scene.name]
        if mine:
            files += plot_scene(folder, scene.name, mine, metric)
        row = None if target is None else fastest_meeting(mine, metric, target)
        if row is None or target is None:
            remove_target_plan(folder, scene.name)
        else:
            plans[scene.name] = write_target_plan(folder, sweep, row, metric, target)
            files.append(plans[scene.name])
    files.append(write_report(folder, render(sweep, rows, target=target, plans=plans)))
    return files, plans
