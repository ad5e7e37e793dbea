"""Fly scans against stop-and-go, measured end to end: samples per instrument hour, the
error at equal instrument time, why the error gains less than the sample count, and the
bias motion blur leaves in the recovered BRDF.

Every figure comes from `gonio tradeoff` sweeps (plan → simulated acquisition →
reconstruction by linear interpolation → log-RMSE on the sweep's 20 000 test pairs, every
pair scored: one outside the samples' support takes the nearest sample's value), each
plan's target fitted to a budget of predicted instrument time (`minutes`), on the glossy
gold and the matte scene with motion blur and timestamp jitter modelled
(configs/scenes/glossy_metal_fly.yaml, matte_fly.yaml):

- configs/sweeps/fly_trade.yaml (arch rig): stop-and-go Sobol or warped targets in
  Rusinkiewicz's or the hybrid parametrization at 10 or 50 ms, against fly detector arcs
  (100 readings a second, 10 ms each) at blur budgets of 0.25, 0.5 and 1° (1° at 5
  minutes only, and 0.5° only at 45) and fly lines along θh at fixed (θd, φd) that
  every axis follows (`fly.segment: theta_h_line`) at 0.5 and 1°; 5, 15 and 45 minutes;
- configs/sweeps/fly_trade_in_plane.yaml: the same at 5 minutes on the in-plane rig
  (matte scene), for the samples per hour;
- configs/sweeps/fly_trade_why.yaml: uniform stop-and-go plans of 4 000 and 16 000
  targets with no time budget, and the 5-minute fly plan with no effect modelled;
- the quick plan (configs/plans/quick.yaml) against the quick plan measured while moving
  (configs/plans/quick_fly.yaml: lines along θh; configs/plans/quick_mixed.yaml: lines
  and a stop-and-go fill), acquired once each.

"Best" is the lowest log-RMSE over the axes swept for that motion. Samples per hour are
the samples measured over the simulated instrument time (the engine's clock: moves,
settling, calibration, integration).

The blur study holds the plan fixed and changes only the blur: a fly plan of --blur-readings
readings (arch rig with its velocity limits ×10, so the blur budget alone sets the sweep's
velocity: smear = velocity × 10 ms) is acquired twice with the same seed, with motion
blur modelled and without, no other effect (no noise), on the glossy gold material at
GGX widths α from 0.02 to 0.5 (time nodes at most 0.05°, or an eighth of
the smear, apart); the bias is log(f blurred / f sharp), on the samples and
on the linear reconstructions of the two runs over the test pairs (RMS over every pair,
and over the mirror region of `gonio.reconstruct.regions`). The planner's default
velocity rule,
`gonio.planner.blur.blur_budget_of_width` (a plan naming its lobe's width), is the smear
K · α · √tolerance with K = 233° from studies/fly_blur.py; the last table shows the
largest smear measured within 0.5 % on every sample and on the recovered mirror region,
and the K of each.

Run: .venv/bin/python studies/fly_trade.py [--runs runs/fly_trade] [--jobs 1]
     [--blur-readings 3000] [--img docs/img] [--stored-only]
(a sweep's finished combinations, and the blur study's, are kept in --runs and not run
again)
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import statistics
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio import progress as planning
from gonio.analysis import Measured, figures
from gonio.planner import BLUR_K_DEG, PlanSpec, blur_budget_deg, build, load_plan
from gonio.reconstruct import evaluate, reconstruction, region_masks, testset
from gonio.rig import Rig
from gonio.scene import Scene, load_scene
from gonio.tradeoff import Sweep, load_sweep, open_store, run_sweep, scaled_rig
from gonio.workflows import simulate_plan

ROOT = Path(__file__).resolve().parents[1]
SWEEPS = ROOT / "configs" / "sweeps"
TRADE, IN_PLANE, WHY = "fly_trade", "fly_trade_in_plane", "fly_trade_why"
#: The targets of the error at equal time: fly's log-RMSE lower by these factors (per
#: scene and budget in minutes; 1 elsewhere: at least as good).
TARGETS = {("glossy-metal-fly", 5.0): 2.0, ("glossy-metal-fly", 15.0): 3.0,
           ("glossy-metal-fly", 45.0): 3.0}  # fmt: skip
#: The blur study: GGX widths, smear budgets (°), the rig's velocity factor.
ALPHAS = (0.02, 0.05, 0.2, 0.5)
SMEARS_DEG = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0)
FAST = 10.0
TOLERANCE = 0.005


def rows_of(name: str, runs: Path, jobs: int, stored_only: bool) -> list[dict[str, Any]]:
    """The rows of sweep ``name``, running what ``runs/name`` does not hold yet (with
    ``stored_only``, the rows it holds, the others counted as not run)."""
    sweep = sweep_and_rig(name)[0]
    folder = runs / name
    started = time.perf_counter()
    if stored_only:
        with open_store(folder) as store:
            rows = [store.rows[t.id] for t in sweep.tasks if t.id in store.rows]
        have = {r["id"] for r in rows}
        missing = [t for t in sweep.tasks if t.id not in have]
        print(f"sweep {name}: {len(rows)} of {len(sweep.tasks)} combinations in {folder}")
        for task in missing:
            i = task.inputs
            what = describe_row(i) if i["motion"] == "fly" or i["exposure_s"] else i["motion"]
            print(f"  not run: {i['scene']}, {i['minutes']} min, {what}")
    else:
        result = run_sweep(sweep, folder, jobs=jobs)
        rows = result.rows
        print(
            f"sweep {name}: {len(rows)} combinations ({result.ran} run now in "
            f"{time.perf_counter() - started:.0f} s, {result.reused} reused from {folder})"
        )
    for row in rows:
        if row["error"]:
            print(f"  failed: {row['id']} {row['error']}")
    return [r for r in rows if not r["error"]]


def per_hour(row: dict[str, Any]) -> float:
    return float(3600.0 * row["measured"] / row["instrument_s"])


def describe_row(row: dict[str, Any]) -> str:
    method = f", {row['method']}" if row.get("method") else ""
    if row["motion"] == "fly":
        kind = "θh lines" if row.get("segment") == "theta_h_line" else "detector arcs"
        return f"{kind} {row['blur_deg']:g}° {row['rate_hz']:g} Hz{method}"
    return f"{row['parametrization']} {row['sampling']} {1000 * row['exposure_s']:g} ms{method}"


def best(rows: Sequence[dict[str, Any]], metric: str = "log_rmse") -> dict[str, Any] | None:
    scored = [r for r in rows if isinstance(r.get(metric), float)]
    return min(scored, key=lambda r: r[metric]) if scored else None


@functools.cache
def sweep_and_rig(name: str) -> tuple[Sweep, Rig]:
    """The sweep file ``name`` and its rig, read once for all its rows."""
    rig = Rig.from_yaml(
        ROOT / "configs" / "rigs" / ("arch.yaml" if name == TRADE else "in_plane.yaml")
    )
    return load_sweep(SWEEPS / f"{name}.yaml"), rig


def streamed(row: dict[str, Any], name: str) -> int:
    """The readings a fly row's plan streams (kept and thinned out): the plan of its
    combination at the target it asked, built again (plans are deterministic)."""
    sweep, rig = sweep_and_rig(name)
    spec = sweep.task(row["id"]).plan_spec()
    sampling = spec.sampling.model_copy(update={"target": row["asked"]})
    with planning.quiet():
        plan = build(spec.model_copy(update={"sampling": sampling}), rig)
    assert plan.summary.fly is not None and len(plan) == row["targets"]
    return plan.summary.fly.streamed


def samples_per_hour(trade: list[dict[str, Any]], in_plane: list[dict[str, Any]]) -> None:
    print("\n## Samples per instrument hour\n")
    print(
        "Samples measured per hour of simulated instrument time: every stop-and-go row at "
        "10 ms and every fly row (100 readings a second, 10 ms each), at each budget; the "
        "median over the rows (scenes, parametrizations, strategies, blur budgets, "
        "methods), per kind of fly plan. A detector-arc plan keeps the readings its thinning "
        "selects (the samples, uniform in the plan's coordinates), a θh-line plan those at "
        "least half the blur budget apart along θh; the detector streams more: streamed /h "
        "counts them all.\n"
    )
    print(
        "| rig | budget (min) | stop-and-go /h | rows | fly | fly samples /h | × | "
        "fly streamed /h | × | fly rows |"
    )
    print("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|")
    kinds = {"detector_arc": "detector arcs", "theta_h_line": "θh lines"}
    for rig, name, rows in (("arch", TRADE, trade), ("in-plane", IN_PLANE, in_plane)):
        for minutes in sorted({r["minutes"] for r in rows}):
            mine = [r for r in rows if r["minutes"] == minutes]
            stop = [per_hour(r) for r in mine if r["motion"] == "stop" and r["exposure_s"] == 0.01]
            for segment, kind in kinds.items():
                flies = [r for r in mine if r["motion"] == "fly" and r["segment"] == segment]
                if not stop or not flies:
                    continue
                s = statistics.median(stop)
                f = statistics.median(per_hour(r) for r in flies)
                g = statistics.median(3600.0 * streamed(r, name) / r["instrument_s"] for r in flies)
                print(
                    f"| {rig} | {minutes:g} | {s:,.0f} | {len(stop)} | {kind} | {f:,.0f} | "
                    f"{f / s:.1f} | {g:,.0f} | {g / s:.1f} | {len(flies)} |"
                )


def equal_time(trade: list[dict[str, Any]]) -> None:
    print("\n## Error at equal instrument time\n")
    print(
        "Per scene and budget, the best stop-and-go row and the best fly row (lowest "
        "log-RMSE over the axes swept), their samples, simulated instrument time, "
        "log-RMSE over every test pair (a pair outside the samples' support takes the "
        "nearest sample's value) and in the mirror region, and coverage (the share of "
        "test pairs inside the reconstruction's support); × is stop-and-go's error over "
        "fly's (the target: ≥ 3 on the glossy gold at 15 and 45 minutes, ≥ 2 at 5; on the "
        "matte at least as good, ≥ 1, or the choice of stop-and-go), and arcs × the same "
        "for the best detector-arc row alone.\n"
    )
    print(
        "| scene | budget (min) | best stop-and-go | samples | log-RMSE | mirror | coverage "
        "| best fly | lines | samples | log-RMSE | mirror | coverage | × | target | arcs × |"
    )
    print("|---|---:|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|---:|")
    for scene in dict.fromkeys(r["scene"] for r in trade):
        for minutes in sorted({r["minutes"] for r in trade}):
            mine = [r for r in trade if r["scene"] == scene and r["minutes"] == minutes]
            stop = best([r for r in mine if r["motion"] == "stop"])
            fly = best([r for r in mine if r["motion"] == "fly"])
            arcs = best(
                [r for r in mine if r["motion"] == "fly" and r["segment"] != "theta_h_line"]
            )
            if stop is None:
                continue
            left = (
                f"| {scene} | {minutes:g} | {describe_row(stop)} | {stop['measured']:,} | "
                f"{stop['log_rmse']:.4f} | {stop['mirror_log_rmse']:.3g} | "
                f"{stop['coverage']:.2f} |"
            )
            if fly is None:
                print(left + " not run | | | | | | | |")
                continue
            ratio = stop["log_rmse"] / fly["log_rmse"]
            target = TARGETS.get((scene, minutes), 1.0)
            print(
                left + f" {describe_row(fly)} | {fly.get('lines')} | {fly['measured']:,} | "
                f"{fly['log_rmse']:.4f} | {fly['mirror_log_rmse']:.3g} | "
                f"{fly['coverage']:.2f} | {ratio:.2f} | "
                f"{'met' if ratio >= target else f'not met (≥ {target:g})'} | "
                + ("—" if arcs is None else f"{stop['log_rmse'] / arcs['log_rmse']:.2f}")
                + " |"
            )
    print("\nEvery row:\n")
    print(
        "| scene | budget (min) | plan | samples | instrument time (s) | log-RMSE | mirror "
        "| grazing | coverage |"
    )
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|")
    for r in sorted(trade, key=lambda r: (r["scene"], r["minutes"], r["motion"], r["log_rmse"])):
        print(
            f"| {r['scene']} | {r['minutes']:g} | {describe_row(r)} | {r['measured']:,} | "
            f"{r['instrument_s']:.0f} | {r['log_rmse']:.4f} | {r['mirror_log_rmse']:.3g} | "
            f"{r['grazing_log_rmse']:.3g} | {r['coverage']:.2f} |"
        )


def why(trade: list[dict[str, Any]], extra: list[dict[str, Any]]) -> None:
    print("\n## Why fly gains less than its sample count\n")
    print(
        "The 5-minute fly plans against uniform Sobol stop-and-go plans of 4 000 and 16 000 "
        "targets with no time budget (what as many samples give when spread uniformly), "
        "and the 0.5° fly plan with no effect modelled (no noise, blur or jitter: what "
        "its lines' layout alone allows). Lines: the anchors the plan sweeps through; "
        "coverage: the share of test pairs inside the reconstruction's support.\n"
    )
    print(
        "| scene | plan | samples | lines | instrument time (s) | log-RMSE | mirror | grazing "
        "| coverage |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for scene in dict.fromkeys(r["scene"] for r in trade):
        fly = [r for r in trade if r["scene"] == scene and r["motion"] == "fly"]
        rows = [*(r for r in fly if r["minutes"] == 5), *(r for r in extra if r["scene"] == scene)]
        for r in sorted(rows, key=lambda r: (r["motion"], r["measured"])):
            label = describe_row(r) + (", no effect" if r["effects"] == "none" else "")
            label += "" if r["minutes"] is None else f", {r['minutes']:g} min"
            lines = "—" if r.get("lines") is None else f"{r['lines']}"
            print(
                f"| {scene} | {label} | {r['measured']:,} | {lines} | "
                f"{r['instrument_s']:.0f} | {r['log_rmse']:.4f} | {r['mirror_log_rmse']:.3g} | "
                f"{r['grazing_log_rmse']:.3g} | {r['coverage']:.2f} |"
            )


def quick_plans(runs: Path, stored_only: bool) -> None:
    """The quick plan against the quick plan measured while moving (module docstring);
    each kept in ``runs/quick.json``."""
    print("\n## The quick plan measured while moving\n")
    print(
        "configs/plans/quick.yaml (500 Sobol targets in the hybrid coordinates, 50 ms) "
        "against configs/plans/quick_fly.yaml (its lines along θh, 1° blur budget, about "
        "3 500 readings) and configs/plans/quick_mixed.yaml (about 4 200 line readings, "
        "then 50 stop-and-go targets where the lines leave gaps), each acquired once on "
        "the glossy gold with blur and jitter "
        "(run seed 7), reconstructed and scored on every one of the 20 000 test pairs; × "
        "is the stop-and-go plan's best log-RMSE over the fly plan's (the target: ≥ 2, "
        "rbf or the lines method, with the stop-and-go plan given at least the fly "
        "plan's instrument time).\n"
    )
    print("| plan | samples | instrument time | method | log-RMSE | mirror | coverage |")
    print("|---|---:|---:|---|---:|---:|---:|")
    cache_path = runs / "quick.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    rig = Rig.from_yaml(ROOT / "configs" / "rigs" / "arch.yaml")
    tests = testset.draw(rig, isotropic=True, size=20_000, seed=14)
    scene = load_scene(ROOT / "configs" / "scenes" / "glossy_metal_fly.yaml")
    best: dict[str, float] = {}
    plans = (("quick", ("linear", "rbf")), ("quick_fly", ("rbf", "lines")),
             ("quick_mixed", ("rbf",)))  # fmt: skip
    for name, methods in plans:
        if name not in cache:
            if stored_only:
                print(f"| {name} | not run | | | | | |")
                continue
            path = ROOT / "configs" / "plans" / f"{name}.yaml"
            spec, plan_rig = load_plan(path)
            with planning.quiet():
                plan = build(spec, plan_rig)
            run = simulate_plan(plan, scene, 7).run
            measured = Measured.from_run(run)
            rows = []
            for method in methods:
                surface = reconstruction(measured, method, None, extrapolate="nearest")
                scored = evaluate(surface, measured.scene_truth(), rig, isotropic=True,
                                  test_set=tests)  # fmt: skip
                rows.append([method, scored.regions["all"].scores.log_rmse,
                             scored.regions["mirror"].scores.log_rmse,
                             scored.regions["all"].coverage])  # fmt: skip
            cache[name] = {"samples": len(run), "seconds": figures(run)["instrument_time_s"],
                           "rows": rows}  # fmt: skip
            cache_path.write_text(json.dumps(cache, indent=1))
        got = cache[name]
        for method, error, mirror, cover in got["rows"]:
            best[name] = min(best.get(name, math.inf), error)
            print(
                f"| {name} | {got['samples']:,} | {got['seconds']:.0f} s | {method} | "
                f"{error:.4f} | {mirror:.3g} | {cover:.2f} |"
            )
    for fly in ("quick_fly", "quick_mixed"):
        if "quick" in best and fly in best:
            ratio = best["quick"] / best[fly]
            print(
                f"\n{fly}: × = {ratio:.1f} ({'met' if ratio >= 2 else 'not met'}: "
                f"{cache[fly]['seconds']:.0f} s against the stop-and-go plan's "
                f"{cache['quick']['seconds']:.0f} s)"
            )


def blur_scene(alpha: float, smear: float | None) -> Scene:
    """The glossy gold with GGX width ``alpha``, no effect but motion blur when a smear
    is given (time nodes at most 0.05° or an eighth of the smear apart)."""
    base = load_scene(ROOT / "configs" / "scenes" / "glossy_metal_fly.yaml")
    data = base.model_dump()
    material = {"name": "cook_torrance", **data["material"]["params"], "alpha": alpha}
    step = max(0.05, smear / 8) if smear is not None else None
    effects = {"motion_blur": {"max_step_deg": step}} if step is not None else {}
    return Scene.model_validate({**data, "material": material, "effects": effects})


def blur_study(readings: int, img: Path, runs: Path, stored_only: bool = False) -> None:
    """The blur study (module docstring); each (α, smear) kept in ``runs/blur.json``."""
    print("\n## The bias motion blur leaves\n")
    arch = ROOT / "configs" / "rigs" / "arch.yaml"
    rig = Rig.from_yaml(arch, raw=scaled_rig(Rig.from_yaml(arch), FAST))
    tests = testset.draw(rig, isotropic=True, size=20_000, seed=14)
    print(
        f"{readings:,} readings per plan, the arch rig ×{FAST:g} faster, no noise; bias = "
        "log(blurred / sharp): RMS and largest |·| on the samples, RMS over every test "
        "pair and over the mirror region of the linear reconstructions.\n"
    )
    print(
        "| α | smear budget (°) | smear max (°) | velocity (°/s) | samples RMS % | samples max % "
        "| recovered RMS % | recovered mirror RMS % |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    table: dict[float, list[tuple[float, float, float, float, float]]] = {}
    cache_path = runs / "blur.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    for alpha in ALPHAS:
        sharp_scene = blur_scene(alpha, None)
        for smear in SMEARS_DEG:
            key = f"{alpha:g} {smear:g} {readings}"
            if key in cache:
                fly_smear, fly_speed, *kept = cache[key]
                table.setdefault(alpha, []).append((fly_smear, *kept))
                print(
                    f"| {alpha:g} | {smear:g} | {fly_smear:.3g} | {fly_speed:.3g} | "
                    f"{kept[0]:.3g} | {kept[1]:.3g} | {kept[2]:.3g} | {kept[3]:.3g} |"
                )
                continue
            if stored_only:
                print(f"| {alpha:g} | {smear:g} | not run | | | | | |")
                continue
            spec = PlanSpec.model_validate(
                {
                    "name": "blur",
                    "parametrization": "rusinkiewicz",
                    "sampling": {"strategy": "fly", "target": readings, "seed": 1,
                                 "fly": {"rate_hz": 100, "blur_deg": smear}},
                }
            )  # fmt: skip
            with planning.quiet():
                plan = build(spec, rig)
            fly = plan.summary.fly
            assert fly is not None
            scenes = (sharp_scene, blur_scene(alpha, smear))
            acquired = [simulate_plan(plan, s, 7).run for s in scenes]
            sharp, blurred = (Measured.from_run(r) for r in acquired)
            assert len(sharp.f) == len(blurred.f)
            ok = (sharp.f > 0) & (blurred.f > 0)
            on_samples = np.log(blurred.f[ok] / sharp.f[ok])
            surfaces = [reconstruction(m, "linear", None) for m in (sharp, blurred)]
            fs, fb = (np.asarray(s.eval(tests.wi, tests.wo)) for s in surfaces)
            good = np.isfinite(fs) & np.isfinite(fb) & (fs > 0) & (fb > 0)
            recovered = np.log(fb[good] / fs[good])
            mirror = region_masks(tests.wi, tests.wo)["mirror"][good]
            row = (
                100 * float(np.sqrt(np.mean(on_samples**2))),
                100 * float(np.abs(on_samples).max()),
                100 * float(np.sqrt(np.mean(recovered**2))),
                100 * float(np.sqrt(np.mean(recovered[mirror] ** 2))) if mirror.any() else math.nan,
            )
            table.setdefault(alpha, []).append((fly.smear_max_deg, *row))
            cache[key] = [fly.smear_max_deg, fly.velocity_max_deg_s, *row]
            cache_path.write_text(json.dumps(cache, indent=1))
            print(
                f"| {alpha:g} | {smear:g} | {fly.smear_max_deg:.3g} | "
                f"{fly.velocity_max_deg_s:.3g} | {row[0]:.3g} | {row[1]:.3g} | {row[2]:.3g} | "
                f"{row[3]:.3g} |",
                flush=True,
            )
    print(
        f"\nThe largest smear with every sample within {100 * TOLERANCE:g} %, and with the "
        f"recovered BRDF's RMS bias in the mirror region within {100 * TOLERANCE:g} % "
        "(interpolated log-log between the smears measured), each with its K = smear / "
        "(α √tolerance), against the planner's budget blur_budget_deg(α, 0.005):\n"
    )
    print(
        "| α | every sample within 0.5 % (°) | K (°) | recovered mirror RMS within 0.5 % (°) "
        "| K (°) | planner's budget (°) |"
    )
    print("|---:|---:|---:|---:|---:|---:|")
    for alpha, rows in table.items():
        smears = np.array([r[0] for r in rows])
        cells = []
        for column in (2, 4):
            limit = _crossing(smears, np.array([r[column] for r in rows]) / 100, TOLERANCE)
            if limit is None:
                cells += [f"beyond {smears.max():g}", "—"]
            else:
                cells += [f"{limit:.3g}", f"{limit / (alpha * math.sqrt(TOLERANCE)):.0f}"]
        print(f"| {alpha:g} | {' | '.join(cells)} | {blur_budget_deg(alpha, TOLERANCE):.3g} |")
    print(f"\n(the planner's K = {BLUR_K_DEG:g}°)")
    plot_blur(table, img / "fly_trade_blur.png")


def _crossing(x: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """The smallest x where y (increasing with x, log-log interpolated) reaches level."""
    above = np.flatnonzero(y >= level)
    if not above.size:
        return None
    k = int(above[0])
    if k == 0:
        return float(x[0]) if y[0] == level else None
    lx, ly = np.log(x[k - 1 : k + 1]), np.log(np.maximum(y[k - 1 : k + 1], 1e-300))
    t = (math.log(level) - ly[0]) / (ly[1] - ly[0])
    return float(np.exp(lx[0] + t * (lx[1] - lx[0])))


def plot_blur(
    table: dict[float, list[tuple[float, float, float, float, float]]], out: Path
) -> None:
    import matplotlib  # the docs extra

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.8), constrained_layout=True)
    for k, (alpha, rows) in enumerate(table.items()):
        colour = f"C{k}"
        smear = [r[0] for r in rows]
        axes[0].loglog(smear, [r[2] for r in rows], "o-", color=colour, label=f"α = {alpha:g}")
        axes[1].loglog(smear, [r[4] for r in rows], "o-", color=colour, label=f"α = {alpha:g}")
        budget = blur_budget_deg(alpha, TOLERANCE)
        for ax in axes:
            ax.axvline(budget, color=colour, lw=0.8, ls=":")
    axes[0].axhline(100 * TOLERANCE, color="0.5", lw=0.8, ls="--")
    axes[0].set_title("largest bias on the samples", fontsize=9)
    axes[1].set_title("RMS bias of the recovered BRDF, mirror region", fontsize=9)
    for ax in axes:
        ax.set_xlabel("smear during one reading (°)")
        ax.set_ylabel("|log(blurred / sharp)| (%)")
        ax.tick_params(labelsize=7)
    axes[0].legend(fontsize=7)
    fig.suptitle("motion blur bias (dotted: the planner's budget at 0.5 %)", fontsize=9)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    _report.figure(out, "Motion blur bias against smear and lobe width")


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=Path, default=ROOT / "runs" / "fly_trade")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--blur-readings", type=int, default=3000)
    parser.add_argument("--img", type=Path, default=ROOT / "docs" / "img")
    parser.add_argument("--skip-blur", action="store_true")
    parser.add_argument(
        "--stored-only", action="store_true", help="report what --runs holds; run nothing"
    )
    args = parser.parse_args()
    print(describe())
    args.runs.mkdir(parents=True, exist_ok=True)
    trade = rows_of(TRADE, args.runs, args.jobs, args.stored_only)
    in_plane = rows_of(IN_PLANE, args.runs, args.jobs, args.stored_only)
    extra = rows_of(WHY, args.runs, args.jobs, args.stored_only)
    samples_per_hour(trade, in_plane)
    equal_time(trade)
    why(trade, extra)
    quick_plans(args.runs, args.stored_only)
    if not args.skip_blur:
        blur_study(args.blur_readings, args.img, args.runs, args.stored_only)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Fly scans against stop-and-go, measured")
