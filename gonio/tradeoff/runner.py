"""One combination of a sweep → one results row: plan it (`gonio.planner.build`),
acquire it on the simulated backend in memory (`gonio.workflows.simulate.simulate_plan`: the engine,
journal and calibration of `gonio acquire`), reconstruct it
(`gonio.reconstruct.methods`) and score it against the scene's truth on the sweep's test
set (`gonio.reconstruct.evaluate`).

A row depends only on its task: the same task gives the same row, bit for bit, in any
process on any machine, except for the wall times (`WALL_COLUMNS`). A combination the
library refuses (`GonioError`: nothing reachable, no sample, …) is a row too, with the
reason in ``error`` and no figures; anything else is a bug and propagates. A figure
that is not a finite number is None (empty in the CSV).
"""

from __future__ import annotations

import math
import time
from functools import lru_cache
from pathlib import Path
from typing import Any

from gonio import progress as planning
from gonio.analysis import Measured, figures
from gonio.errors import GonioError
from gonio.planner import MAX_TARGETS, Plan, PlanSpec, build
from gonio.reconstruct import METRICS, REGIONS, TestSet, evaluate, reconstruction, testset
from gonio.rig import Rig
from gonio.scene import load_scene
from gonio.tradeoff.grid import Task
from gonio.workflows import simulate_plan

#: The figures of a row after its inputs: the target the plan asked (fitted under a
#: time budget), counts, predicted and simulated instrument time (s), why the ordering
#: stopped, a fly plan's lines and sweeps (None stop-and-go), then each metric and
#: coverage, over every test pair ("log_rmse", "coverage", …) and by region
#: ("mirror_log_rmse", …).
SCORE_COLUMNS = tuple(
    f"{'' if region == 'all' else f'{region}_'}{name}"
    for region in ("all", *REGIONS)
    for name in (*METRICS, "coverage")
)
FIGURE_COLUMNS = (
    "asked",
    "targets",
    "measured",
    "skipped",
    "saturated",
    "predicted_s",
    "instrument_s",
    "ordering",
    "lines",
    "sweeps",
    *SCORE_COLUMNS,
    "error",
)
#: Plannings at most to fit a target to a time budget, and the share of the budget a
#: fitted plan may leave unused.
FIT_TRIES, FIT_SLACK = 8, 0.03

#: Wall-clock seconds: planning, acquiring, reconstructing and scoring, and in all (the
#: only columns that differ between two runs of the same task).
WALL_COLUMNS = ("plan_wall_s", "acquire_wall_s", "evaluate_wall_s", "wall_s")


def run(task: Task) -> dict[str, Any]:
    """The results row of ``task`` (see the module docstring)."""
    started = time.perf_counter()
    row: dict[str, Any] = dict(task.inputs)
    row.update(dict.fromkeys(FIGURE_COLUMNS))
    walls: dict[str, float | None] = dict.fromkeys(WALL_COLUMNS)
    try:
        row.update(_measure(task, walls))
        row["error"] = ""
    except GonioError as exc:
        row["error"] = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    walls["wall_s"] = time.perf_counter() - started
    row.update(walls)
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in row.items()}


def _measure(task: Task, walls: dict[str, float | None]) -> dict[str, Any]:
    rig = _rig(task.rig_path, task.rig_text)
    scene = load_scene(Path(task.scene_path), rig, raw=task.scene_text).with_effects(task.effects)
    started = time.perf_counter()
    with planning.quiet():
        where = f"combination {task.id}"
        if task.budget_s is None:
            plan = build(task.plan_spec(), rig, where=where)
        else:
            plan = fit_to_budget(task.plan_spec(), rig, task.budget_s, where=where)
        asked = plan.spec.sampling.target
    walls["plan_wall_s"] = time.perf_counter() - started
    result = simulate_plan(plan, scene, task.run_seed)
    plan = result.run.plan  # an adaptive plan's survey is followed by its second pass
    walls["acquire_wall_s"] = result.wall_s
    started = time.perf_counter()
    measured = Measured.from_run(result.run)
    candidate = reconstruction(measured, task.method, None, extrapolate=task.extrapolate)
    scored = evaluate(
        candidate,
        measured.scene_truth(),
        rig,
        isotropic=plan.spec.isotropic,
        test_set=_test_set(
            task.rig_path, task.rig_text, plan.spec.isotropic, task.test_pairs, task.test_seed
        ),
        candidate_label=f"{task.method} ({task.id})",
        only_supported=task.only_supported,
    )
    walls["evaluate_wall_s"] = time.perf_counter() - started
    run_figures = figures(result.run)
    fly = plan.summary.fly
    out: dict[str, Any] = {
        "asked": asked,
        "targets": len(plan),
        "measured": run_figures["measured"],
        "skipped": run_figures["skipped"],
        "saturated": run_figures["saturated"],
        "predicted_s": plan.summary.total_s,
        "instrument_s": run_figures["instrument_time_s"],
        "ordering": plan.summary.stopped,
        "lines": None if fly is None else fly.lines,
        "sweeps": None if plan.sweeps is None else len(plan.sweeps),
    }
    for region, figures_of in scored.regions.items():
        prefix = "" if region == "all" else f"{region}_"
        for name in METRICS:
            out[f"{prefix}{name}"] = getattr(figures_of.scores, name)
        out[f"{prefix}coverage"] = figures_of.coverage
    return out


def fit_to_budget(spec: PlanSpec, rig: Rig, budget_s: float, *, where: str) -> Plan:
    """The plan of ``spec`` whose target is fitted to an instrument-time budget.

    Parameters
    ----------
    spec : PlanSpec
        The plan; its ``sampling.target`` is the first guess.
    rig : Rig
        The rig it is planned on.
    budget_s : float
        The instrument time (s) the planner's predicted duration must fit.
    where : str
        Names the plan in an error.

    Returns
    -------
    Plan
        The plan of the largest target tried (at most `FIT_TRIES` plannings, each target
        scaled by budget / predicted duration, kept between the largest that fits and the
        least that does not, else halfway) whose predicted duration is within the budget;
        the first within `FIT_SLACK` of it ends the search. `GonioError` when none fits.
    """
    target = spec.sampling.target or 1
    fitted: Plan | None = None
    low, high = 0, MAX_TARGETS + 1  # the largest target known to fit, the least known not to
    for _ in range(FIT_TRIES):
        sampling = spec.sampling.model_copy(update={"target": target})
        plan = build(spec.model_copy(update={"sampling": sampling}), rig, where=where)
        total = plan.summary.total_s
        if total <= budget_s:
            low = target
            if fitted is None or len(plan) > len(fitted):
                fitted = plan
            if total >= (1.0 - FIT_SLACK) * budget_s:
                break
        else:
            high = target
        # the proportional guess, kept strictly between what fits and what does not
        guess = int(target * budget_s / max(total, 1e-9) * (1.0 - 0.5 * FIT_SLACK))
        if not low < guess < high:
            guess = (low + high) // 2 if high <= MAX_TARGETS else 2 * low
        if not low < guess < high:
            break
        target = guess
    if fitted is None:
        raise GonioError(f"{where}: no target of this plan fits {budget_s:g} s of instrument time")
    return fitted


@lru_cache(maxsize=8)
def _rig(path: str, text: bytes) -> Rig:
    return Rig.from_yaml(path, raw=text)


@lru_cache(maxsize=8)
def _test_set(path: str, text: bytes, isotropic: bool, pairs: int, seed: int) -> TestSet:
    return testset.draw(_rig(path, text), isotropic=isotropic, size=pairs, seed=seed)
