"""The shipped study's engine parts (docs/explanations/tradeoff.md "The study"): tables
and figures from the results.csv of `gonio tradeoff` runs of configs/sweeps/study_*.yaml,
with the noise-free curves of studies/study.py placed on the instrument-time axis.

    uniform   per scene and parametrization: instrument time and log-RMSE, noise on and
              off, against the samples measured; the instrument time fitted (t = floor·n
              + c·n^p: settle and exposure, then the moves and calibrations as a power
              law fitted log-log) and the time each parametrization needs for log-RMSE
              0.01 and 0.03 (from the noise-free curves; beyond 4 000 samples by that
              fit, an extrapolation); one PNG per scene
    exposure  error against instrument time for each exposure, and the best row within
              each time budget
    effects   per effect: simulated wall time per sample and the change of the error
    timing    per effect: the simulated acquisition's wall time per sample, measured in
              one process one run after another (the sweep's wall times vary with load)
    adaptive  uniform against adaptive plans of the same parametrization, method and
              count (configs/sweeps/study_adaptive.yaml): log-RMSE noise on and off,
              the error ratio and the instrument time of each

Run: .venv/bin/python studies/study_engine.py uniform --runs DIR ... --curves
runs/study/curves.csv [--img docs/img]; `exposure --runs DIR`; `effects --runs DIR`;
`adaptive --runs DIR`.
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
import sys
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from study import TARGETS, fmt_needed, needed

COLOURS = {"hybrid": "C0", "rusinkiewicz": "C1", "orthographic": "C2", "spherical": "C3"}
#: scene name in a sweep → the scene file stem of studies/study.py
STEMS = {
    "matte": "matte",
    "glossy-metal": "glossy_metal",
    "brushed-metal": "brushed_metal",
    "seed000-specular": "seed000_specular",
}


def rows_of(dirs: list[str]) -> list[dict[str, str]]:
    rows: list[dict[str, str]] = []
    for d in dirs:
        with (Path(d) / "results.csv").open(encoding="utf-8") as fh:
            rows += [r for r in csv.DictReader(fh) if not r["error"]]
    return rows


def fit_time(rows: list[dict[str, str]], floor_s: float) -> tuple[float, float, float]:
    """(floor, c, p) of instrument_s ≈ floor·n + c·n^p: ``floor_s`` per sample (settle and
    exposure) plus the moves and calibrations, a power law fitted log-log (denser plans
    make shorter moves)."""
    n = np.array([float(r["measured"]) for r in rows])
    rest = np.array([float(r["instrument_s"]) for r in rows]) - floor_s * n
    p, log_c = np.polyfit(np.log(n), np.log(rest), 1)
    return floor_s, float(math.exp(log_c)), float(p)


def predict(fit: tuple[float, float, float], n: float) -> float:
    floor_s, c, p = fit
    return floor_s * n + c * n**p


def uniform(args: argparse.Namespace) -> None:
    rows = rows_of(args.runs)
    synthetic: dict[tuple[str, str], dict[int, float]] = defaultdict(dict)
    if args.curves:
        with open(args.curves, encoding="utf-8") as fh:
            for r in csv.DictReader(fh):
                # The uniform curves (an older curves.csv has no sampling column).
                if r["method"] == args.method and r.get("sampling", "sobol") == "sobol":
                    key = (r["scene"], r["parametrization"])
                    synthetic[key][int(r["samples"])] = float(r["log_rmse"])
    for scene in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == scene]
        names = list(dict.fromkeys(r["parametrization"] for r in mine))
        counts = sorted({int(r["samples"]) for r in mine})
        print(f"\n### {scene}: log-RMSE noise on / off, and instrument time (s)\n")
        print("| parametrization | " + " | ".join(f"{n:,}" for n in counts) + " | moves ∝ n^p |")
        print("|---|" + "---:|" * (len(counts) + 1))
        fits = {}
        for name in names:
            ours = [r for r in mine if r["parametrization"] == name]
            fits[name] = fit_time(ours, args.floor)
            cells = []
            for n in counts:
                on = [r for r in ours if int(r["samples"]) == n and r["effects"] == "scene"]
                off = [r for r in ours if int(r["samples"]) == n and r["effects"] == "none"]
                if on and off:
                    cells.append(
                        f"{float(on[0]['log_rmse']):.4f} / "
                        f"{float(off[0]['log_rmse']):.4f} ({float(on[0]['instrument_s']):,.0f})"
                    )
                else:
                    cells.append("—")
            print(f"| {name} | " + " | ".join(cells) + f" | {fits[name][2]:.2f} |")
        stem = STEMS.get(scene, scene)
        if any((stem, name) in synthetic for name in names):
            print(
                f"\n{scene}: noise-free samples and instrument time (extrapolated beyond "
                "4 000 samples) for each target\n"
            )
            targets = args.targets or TARGETS
            heads = " | ".join(f"n for {t} | time for {t}" for t in targets)
            print(f"| parametrization | {heads} |")
            print("|---|" + "---:|---:|" * len(targets))
            for name in names:
                curve = synthetic.get((stem, name), {})
                ns = sorted(curve)
                cells = []
                for target in targets:
                    n = needed(ns, [curve[k] for k in ns], target)
                    hours = "—" if math.isinf(n) else f"{predict(fits[name], n) / 3600:.2f} h"
                    cells += [fmt_needed(n, ns), hours]
                print(f"| {name} | " + " | ".join(cells) + " |")
        if args.img:
            plot(scene, mine, names, fits, synthetic, stem, Path(args.img), args.method)


def plot(
    scene: str,
    rows: list[dict[str, str]],
    names: list[str],
    fits: dict[str, tuple[float, float, float]],
    synthetic: dict[tuple[str, str], dict[int, float]],
    stem: str,
    img: Path,
    method: str,
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.6, 3.6), dpi=90)
    for name in names:
        colour = COLOURS.get(name, "k")
        for effects, marker in (("scene", "o"), ("none", "x")):
            pts = sorted(
                (float(r["instrument_s"]), float(r["log_rmse"]))
                for r in rows
                if r["parametrization"] == name and r["effects"] == effects
            )
            if pts:
                x, y = zip(*pts, strict=True)
                ax.plot(
                    np.array(x) / 3600,
                    y,
                    marker,
                    color=colour,
                    ms=4,
                    mfc="none" if effects == "none" else colour,
                )
        curve = synthetic.get((stem, name))
        if curve:
            ns = sorted(curve)
            ax.plot(
                [predict(fits[name], n) / 3600 for n in ns],
                [curve[n] for n in ns],
                "-",
                color=colour,
                lw=1,
                label=name,
            )
    for target in TARGETS:
        ax.axhline(target, color="0.6", lw=0.6, ls=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("instrument time (h; beyond 4 000 samples extrapolated)")
    ax.set_ylabel("log-RMSE")
    ax.set_title(
        f"{scene}, uniform Sobol: engine, linear (o noise on, x off); noise-free {method} (line)",
        fontsize=8,
    )
    ax.legend(fontsize=7)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    out = img / f"study-{stem}.png"
    fig.savefig(out)
    plt.close(fig)
    _report.figure(out, f"{scene}: log-RMSE against instrument time")


def exposure(args: argparse.Namespace) -> None:
    """Mean log-RMSE and instrument time over replicates, by exposure and sample count;
    then the best (exposure, samples) within each instrument-time budget."""
    rows = rows_of(args.runs)
    for scene in dict.fromkeys(r["scene"] for r in rows):
        cells: dict[tuple[float, int], tuple[float, float, float, float]] = {}
        for key in {(float(r["exposure_s"]), int(r["samples"])) for r in rows}:
            group = [
                r
                for r in rows
                if r["scene"] == scene and (float(r["exposure_s"]), int(r["samples"])) == key
            ]
            if group:
                errs = [float(r["log_rmse"]) for r in group]
                hours = statistics.mean(float(r["instrument_s"]) for r in group) / 3600
                cells[key] = (statistics.mean(errs), min(errs), max(errs), hours)
        exposures = sorted({e for e, _ in cells})
        counts = sorted({n for _, n in cells})
        print(f"\n### {scene}: mean log-RMSE (instrument time, h) by exposure and samples\n")
        print("| exposure s | " + " | ".join(f"{n:,}" for n in counts) + " |")
        print("|---:|" + "---:|" * len(counts))
        for e in exposures:
            row = [
                f"{cells[e, n][0]:.4f} ({cells[e, n][3]:.2f})" if (e, n) in cells else "—"
                for n in counts
            ]
            print(f"| {e:g} | " + " | ".join(row) + " |")
        print("\nbest within each instrument-time budget (mean over replicates):\n")
        print("| budget (h) | samples | exposure s | log-RMSE | min–max | time (h) |")
        print("|---:|---:|---:|---:|---:|---:|")
        for budget_h in args.budgets:
            fit = [k for k, v in cells.items() if v[3] <= budget_h]
            if fit:
                e, n = min(fit, key=lambda k: cells[k][0])
                mean, lo, hi, hours = cells[e, n]
                print(
                    f"| {budget_h:g} | {n:,} | {e:g} | {mean:.4f} | {lo:.4f}–{hi:.4f} | "
                    f"{hours:.2f} |"
                )


def effects(args: argparse.Namespace) -> None:
    rows = rows_of(args.runs)
    for scene in dict.fromkeys(r["scene"] for r in rows):
        mine = [r for r in rows if r["scene"] == scene]
        groups: dict[str, list[dict[str, str]]] = defaultdict(list)
        for r in mine:
            groups[r["effects"]].append(r)
        base = statistics.mean(float(r["log_rmse"]) for r in groups["none"])
        base_ms = statistics.mean(
            1e3 * float(r["acquire_wall_s"]) / float(r["measured"]) for r in groups["none"]
        )
        print(
            f"\n### {scene}: {len(groups['none'])} replicates each; none = "
            f"{base:.4f} log-RMSE, {base_ms:.2f} ms per sample\n"
        )
        print("| effects | ms per sample (acquire) | × none | log-RMSE mean | min–max | vs none |")
        print("|---|---:|---:|---:|---:|---:|")
        for label, group in groups.items():
            errs = [float(r["log_rmse"]) for r in group]
            ms = statistics.mean(
                1e3 * float(r["acquire_wall_s"]) / float(r["measured"]) for r in group
            )
            mean = statistics.mean(errs)
            print(
                f"| {label} | {ms:.2f} | {ms / base_ms:.2f} | {mean:.4f} | "
                f"{min(errs):.4f}–{max(errs):.4f} | {mean - base:+.4f} |"
            )


def timing(args: argparse.Namespace) -> None:
    """Simulated wall time per sample of one plan (Rusinkiewicz Sobol, ``args.samples``
    targets, built once) acquired with no effect, each effect alone and the scene's own,
    in this process one after another (best of ``args.repeats``)."""
    import time

    from gonio import progress as planning
    from gonio.planner import PlanSpec, build
    from gonio.rig import Rig
    from gonio.scene import load_scene
    from gonio.tradeoff import EFFECT_NAMES
    from gonio.workflows import simulate_plan

    root = Path(__file__).resolve().parent.parent
    rig = Rig.from_yaml(root / "configs/rigs/arch.yaml")
    spec = PlanSpec.model_validate(
        {
            "name": "timing",
            "parametrization": "rusinkiewicz",
            "kicks": 50,
            "sampling": {"strategy": "sobol", "target": args.samples, "seed": 1},
        }
    )
    with planning.quiet():
        plan = build(spec, rig)
    print(
        f"\n{len(plan):,} targets; ms per sample of the simulated acquisition, best of "
        f"{args.repeats}\n"
    )
    # Every effect but stray light, which has no default power to switch on.
    names = [n for n in EFFECT_NAMES if n != "stray_light"]
    for stem in args.scenes:
        scene = load_scene(root / f"configs/scenes/{stem}.yaml", rig)
        own = scene.effects.model_dump(mode="json")
        cases: dict[str, dict[str, object]] = {"none": {}}
        cases.update({n: {n: own.get(n) or {}} for n in names})
        cases["scene"] = own
        print(f"| {stem} | " + " | ".join(cases) + " |")
        print("|---|" + "---:|" * len(cases))
        cells = []
        for effects in cases.values():
            variant = scene.with_effects(effects)
            best = math.inf
            for _ in range(args.repeats):
                started = time.perf_counter()
                simulate_plan(plan, variant, 7)
                best = min(best, time.perf_counter() - started)
            cells.append(f"{1e3 * best / len(plan):.2f}")
        print("| ms per sample | " + " | ".join(cells) + " |\n", flush=True)


def adaptive(args: argparse.Namespace) -> None:
    rows = rows_of(args.runs)
    plans: dict[tuple[str, str, str, int, str], dict[str, dict[str, str]]] = defaultdict(dict)
    for r in rows:
        key = (r["scene"], r["parametrization"], r["method"], int(r["samples"]), r["effects"])
        plans[key][r["sampling"]] = r
    print(
        "| scene | effects | samples | uniform | adaptive | uniform / adaptive | "
        "instrument time, uniform → adaptive |"
    )
    print("|---|---|---:|---:|---:|---:|---|")
    for (scene, _, _, n, effects), kinds in sorted(plans.items()):
        if "adaptive" not in kinds or len(kinds) < 2:
            continue
        (other,) = (k for k in kinds if k != "adaptive")
        u, a = kinds[other], kinds["adaptive"]
        eu, ea = float(u["log_rmse"]), float(a["log_rmse"])
        tu, ta = float(u["instrument_s"]), float(a["instrument_s"])
        print(
            f"| {scene} | {effects} | {n:,} | {eu:.3g} | {ea:.3g} | {eu / ea:.1f}× | "
            f"{tu:,.0f} s → {ta:,.0f} s |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("part", choices=("uniform", "exposure", "effects", "timing", "adaptive"))
    parser.add_argument("--runs", nargs="+", default=[], help="gonio tradeoff OUTDIRs")
    parser.add_argument("--scenes", nargs="+", default=["matte", "glossy_metal"])
    parser.add_argument("--samples", type=int, default=1000, help="targets of `timing`")
    parser.add_argument("--repeats", type=int, default=3, help="runs of `timing`")
    parser.add_argument("--curves", help="curves.csv of studies/study.py")
    parser.add_argument("--method", default="linear", help="the curves' method")
    parser.add_argument("--img", help="write PNGs here")
    parser.add_argument("--targets", type=float, nargs="+", help="log-RMSE targets")
    parser.add_argument(
        "--floor", type=float, default=0.25, help="s per sample: settle + exposure × averages"
    )
    parser.add_argument("--budgets", type=float, nargs="+", default=[0.1, 0.2, 0.5, 1.0])
    args = parser.parse_args()
    parts = {
        "uniform": uniform,
        "exposure": exposure,
        "effects": effects,
        "timing": timing,
        "adaptive": adaptive,
    }
    parts[args.part](args)


#: Each part's page title.
TITLES = {
    "uniform": "Uniform plans on the engine: error against samples and instrument time",
    "exposure": "Exposure against sample count at fixed instrument time",
    "effects": "What each simulated effect changes in the error, and costs",
    "timing": "The simulated acquisition's time per sample, effect by effect",
    "adaptive": "Adaptive against uniform plans on the engine",
}


def title(argv: Sequence[str]) -> str:
    return TITLES.get(argv[0] if argv else "", "The study on the engine")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title=title, part=True)
