"""A sweep's figures, one pair per scene (PNG, matplotlib's Agg backend, written
atomically): the error against the simulated instrument time, a colour per
parametrization (and motion, when a sweep has fly combinations) with its own front as a
step line and the scene's front over every one ringed in black; and the error against
the samples measured, each one's median over the other axes (per sample count, or per
time budget) joined by a line."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from gonio.output import reserve_output
from gonio.plots import require_matplotlib
from gonio.tradeoff.front import TIME, pareto_front
from gonio.tradeoff.spec import FLY

#: One colour per parametrization (in the order they first appear).
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def slug(name: str) -> str:
    """A file-name part for a scene's name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", name).strip("-.") or "scene"


def figure_names(scene: str) -> tuple[str, str]:
    """The file names of a scene's two figures."""
    return f"{slug(scene)}-error-vs-time.png", f"{slug(scene)}-error-vs-samples.png"


def series(row: dict[str, Any]) -> str:
    """The series a row is drawn in: its parametrization, and ``fly`` for a fly one."""
    return str(row["parametrization"]) + (" fly" if row.get("motion") == FLY else "")


def _scored(rows: Sequence[dict[str, Any]], metric: str, x: str) -> list[dict[str, Any]]:
    return [
        r
        for r in rows
        if isinstance(r.get(metric), int | float) and isinstance(r.get(x), int | float)
        if r[metric] > 0 and r[x] > 0
    ]


def plot_scene(
    folder: Path, scene: str, rows: Sequence[dict[str, Any]], metric: str
) -> tuple[Path, Path]:
    """Write ``scene``'s two figures into ``folder``; their paths."""
    plt = require_matplotlib()
    paths = tuple(folder / name for name in figure_names(scene))
    names = list(dict.fromkeys(series(r) for r in rows))
    colours = {n: COLOURS[k % len(COLOURS)] for k, n in enumerate(names)}

    fig, ax = plt.subplots(figsize=(7.0, 4.8), constrained_layout=True)
    timed = _scored(rows, metric, TIME)
    for name in names:
        mine = [r for r in timed if series(r) == name]
        if not mine:
            continue
        ax.scatter(
            [r[TIME] for r in mine],
            [r[metric] for r in mine],
            s=14,
            alpha=0.6,
            color=colours[name],
            label=name,
        )
        front = [mine[i] for i in pareto_front(mine, metric)]
        ax.step(
            [r[TIME] for r in front],
            [r[metric] for r in front],
            where="post",
            color=colours[name],
            lw=1.0,
        )
    front = [timed[i] for i in pareto_front(timed, metric)]
    if front:
        ax.scatter(
            [r[TIME] for r in front],
            [r[metric] for r in front],
            s=70,
            facecolors="none",
            edgecolors="k",
            lw=1.2,
            label="front (all)",
        )
    _finish(
        ax, bool(timed), "simulated instrument time (s)", metric, f"{scene}: {metric} against time"
    )
    _save(fig, paths[0])
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7.0, 4.8), constrained_layout=True)
    counted = _scored(rows, metric, "measured")
    for name in names:
        mine = [r for r in counted if series(r) == name]
        if not mine:
            continue
        ax.scatter(
            [r["measured"] for r in mine],
            [r[metric] for r in mine],
            s=14,
            alpha=0.5,
            color=colours[name],
            label=name,
        )
        groups = list(dict.fromkeys((r["samples"], r.get("minutes")) for r in mine))
        points = sorted(
            (
                float(
                    np.median(
                        [r["measured"] for r in mine if (r["samples"], r.get("minutes")) == g]
                    )
                ),
                float(
                    np.median([r[metric] for r in mine if (r["samples"], r.get("minutes")) == g])
                ),
            )
            for g in groups
        )
        ax.plot([x for x, _ in points], [y for _, y in points], color=colours[name], lw=1.2)
    _finish(
        ax,
        bool(counted),
        "samples measured",
        metric,
        f"{scene}: {metric} against samples (medians)",
    )
    _save(fig, paths[1])
    plt.close(fig)
    return paths[0], paths[1]


def _finish(ax: Any, data: bool, xlabel: str, ylabel: str, title: str) -> None:
    if data:  # (log axes without a positive value warn)
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.25)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)


def _save(fig: Any, path: Path) -> None:
    with reserve_output(path, "-o") as pending:
        pending.write_with(lambda p: fig.savefig(p, dpi=100, format="png"))
