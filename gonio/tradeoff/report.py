"""``report.md`` of a sweep: per scene, its figures, the Pareto front of the error
against the simulated instrument time, the best row of each parametrization and, with an
error target, the fastest row meeting it; then the combinations that failed, and why."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from gonio.output import reserve_output
from gonio.tradeoff.front import TIME, best, fastest_meeting, pareto_front
from gonio.tradeoff.grid import Sweep
from gonio.tradeoff.plots import figure_names, series
from gonio.tradeoff.spec import AXIS_NAMES, FLY

REPORT = "report.md"


def _number(value: Any, digits: int = 4) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


def _table(heads: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    lines = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return lines


def _varied(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The axes that take more than one value among ``rows`` (the others are constant)."""
    return [n for n in AXIS_NAMES if len({str(r.get(n)) for r in rows}) > 1]


def _row_cells(row: dict[str, Any], metric: str, axes: Sequence[str]) -> list[str]:
    return [
        _number(row[TIME], 5),
        _number(row["predicted_s"], 5),
        _number(row[metric]),
        str(row["measured"]),
        *(_number(row[a]) for a in axes),
        f"`{row['id']}`",
    ]


def render(
    sweep: Sweep,
    rows: Sequence[dict[str, Any]],
    *,
    target: float | None = None,
    plans: dict[str, Path] | None = None,
) -> str:
    """The report's Markdown for ``rows`` (the sweep's finished rows, in grid order);
    ``plans``: the target plan written for each scene that meets ``target``."""
    spec, metric = sweep.spec, sweep.spec.metric
    failed = [r for r in rows if r.get("error")]
    lines = [
        f"# Sweep {spec.name}: {metric} against instrument time",
        "",
        f"{len(rows)} of {len(sweep.tasks)} combinations finished ({len(failed)} failed) over "
        f"{len(sweep.scenes)} scene{'s' if len(sweep.scenes) != 1 else ''} on rig "
        f"{sweep.rig.spec.name!r}. Error: {metric} on the test set of "
        f"{spec.evaluation.pairs} pairs (seed {spec.evaluation.seed}), "
        + (
            "the pairs inside each reconstruction's support only"
            if spec.evaluation.only_supported
            else f"every pair (outside the support: {spec.evaluation.extrapolate} fill)"
        )
        + "; time: the simulated "
        "instrument time in seconds (predicted: the planner's estimate). Every row is in "
        "results.csv.",
    ]
    varied = _varied(rows)
    constant = [n for n in AXIS_NAMES if n not in varied and rows and rows[0].get(n) is not None]
    if rows and constant:
        fixed = ", ".join(f"{n} {_number(rows[0][n])}" for n in constant)
        lines += ["", f"Constant over the sweep: {fixed}."]
    for scene in sweep.scenes:
        mine = [r for r in rows if r["scene"] == scene.name]
        lines += ["", f"## Scene {scene.name} ({scene.path})", ""]
        if not mine:
            lines.append("No combination of this scene has finished.")
            continue
        axes = _varied(mine)
        time_png, samples_png = figure_names(scene.name)
        lines += [
            f"![{metric} against time]({time_png}) ![{metric} against samples]({samples_png})"
        ]
        heads = ["time s", "predicted s", metric, "measured", *axes, "id"]
        front = [mine[i] for i in pareto_front(mine, metric)]
        lines += ["", f"Pareto front ({len(front)} of {len(mine)} combinations):", ""]
        lines += _table(heads, [_row_cells(r, metric, axes) for r in front])
        fly = any(r.get("motion") == FLY for r in mine)
        lines += ["", f"Best of each parametrization{' and motion' if fly else ''}:", ""]
        per = []
        for name in dict.fromkeys(series(r) for r in mine):
            top = best([r for r in mine if series(r) == name], metric)
            if top is not None:
                per.append(_row_cells(top, metric, axes))
        lines += _table(heads, per)
        if target is not None:
            lines += ["", *_target_lines(mine, metric, target, (plans or {}).get(scene.name))]
    if failed:
        lines += ["", "## Failed combinations", ""]
        reasons = Counter(r["error"] for r in failed)
        lines += _table(["combinations", "reason"], [[str(n), e] for e, n in reasons.items()])
    return "\n".join(lines) + "\n"


def _target_lines(
    rows: Sequence[dict[str, Any]], metric: str, target: float, plan: Path | None
) -> list[str]:
    row = fastest_meeting(rows, metric, target)
    if row is None:
        top = best(rows, metric)
        reached = "no combination scored" if top is None else f"the best reaches {top[metric]:.4g}"
        return [f"No combination meets {metric} ≤ {target:g}: {reached}."]
    where = f" Plan: {plan.parent.name}/{plan.name}." if plan is not None else ""
    return [
        f"Fastest meeting {metric} ≤ {target:g}: `{row['id']}`, {row[metric]:.4g} in "
        f"{row[TIME]:.1f} s ({row['parametrization']}, "
        f"{'fly' if row.get('motion') == FLY else row['sampling']}, "
        f"{row.get('asked') or row['samples']} "
        f"samples, {row['method']}).{where}"
    ]


def write_report(folder: Path, text: str) -> Path:
    path = folder / REPORT
    with reserve_output(path, "-o") as pending:
        pending.write_bytes(text.encode("utf-8"))
    return path
