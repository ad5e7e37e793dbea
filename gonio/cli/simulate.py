"""`gonio simulate PLAN.yaml --scene SCENE.yaml`: measure a plan on the simulated rig
(`sim.session.simulate_plan`) and print what it cost and how accurate it was.

The summary says how long the real rig would take, how long the simulation took, and
how far the recovered BRDF is from the scene's model at the pairs measured: what a plan
and a set of effects cost in accuracy, before any hardware moves.
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np

from gonio.acquire.calibration import geometry_label
from gonio.config import check_output
from gonio.planner.plan import hms, load_plan_source
from sim.scene import load_scene
from sim.session import Result, simulate_plan


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "simulate",
        help=help_,
        description="Plan, then measure every target through the simulated motors and "
        "detector, calibrate with the reference standard, and report instrument time, "
        "wall time and the error of the recovered BRDF.",
    )
    p.add_argument("plan", type=Path, help="the plan file (YAML)")
    p.add_argument("--scene", type=Path, required=True, help="the scene file (YAML)")
    p.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    p.add_argument("--seed", type=int, help="the run's seed (default: the scene's)")
    p.add_argument("--no-effects", action="store_true", help="ignore the scene's effects")
    p.add_argument("-o", "--output", type=Path, help="write one row per target as CSV")
    p.set_defaults(func=cmd_simulate)


def render(result: Result) -> str:
    run, plan, scene = result.run, result.plan, result.scene
    reference = plan.rig.spec.reference
    effects = ", ".join(scene.effects.names()) or "none"
    ok = ~run.saturated & (result.truth > 0)
    error = np.abs(result.brdf[ok] / result.truth[ok] - 1.0)
    lines = [
        f"simulated plan {plan.spec.name!r} on rig {plan.rig.spec.name!r}, "
        f"scene {scene.name!r} (effects: {effects})",
        f"  {'targets':<24}{len(run):>10}",
        f"  {'instrument time':<24}{hms(run.instrument_time_s):>10}   "
        f"(the plan predicted {hms(plan.summary.total_s)})",
        f"  {'wall time':<24}{result.wall_s:>9.2f}s   "
        f"(1/{run.instrument_time_s / max(result.wall_s, 1e-9):,.0f} of the instrument time)",
        f"  {'saturated readings':<24}{int(run.saturated.sum()):>10}",
        f"  {'reference standard':<24}{result.reference_counts:>10.1f}   counts "
        f"(albedo {reference.albedo:g}, {geometry_label(plan.rig)}, "
        f"{result.reference_exposure_s:g} s; "
        f"dark {result.dark_rate:.1f} counts/s; {100 * result.reference_change:+.3f} % "
        "by the end, divided out)",
    ]
    if error.size:
        q50, q95 = np.percentile(error, [50, 95])
        lines.append(
            f"  {'recovered BRDF error':<24}{100 * q50:>9.3f}%   median; "
            f"95th percentile {100 * q95:.3f} %, max {100 * error.max():.3f} % "
            f"(vs the model at the pairs measured, {error.size} unsaturated targets)"
        )
    lines += _point_source_note(result)
    return "\n".join(lines)


def _point_source_note(result: Result) -> list[str]:
    """A point source's ideal chain assumes the detector's spot lies on the sample."""
    rig = result.plan.rig
    if rig.source_kind != "point" or result.scene.effects.footprint is not None:
        return []
    fov, sample = rig.spec.constraints.detector_fov_mm, rig.spec.constraints.sample_diameter_mm
    beyond = int(np.count_nonzero(fov > sample * result.run.wo[:, 2]))
    if not beyond:
        return []
    limit = math.degrees(math.acos(min(fov / sample, 1.0)))
    return [
        f"  note: {beyond} targets see past the sample's edge (θo > {limit:.1f}°); the "
        "ideal point-source chain counts that area as lit sample: list the footprint "
        "effect to model it"
    ]


def write_csv(result: Result, path: Path) -> None:
    run, rig = result.run, result.plan.rig
    header = [
        "index",
        *(f"{a}_commanded_rad" for a in rig.axes),
        *(f"{a}_read_back_rad" for a in rig.axes),
        "wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z",
        "exposure_s", "averages", "counts", "counts_std", "saturated",
        "brdf", "brdf_truth", "settled_s",
    ]  # fmt: skip
    with path.open("w", newline="", encoding="utf-8") as f:
        out = csv.writer(f)
        out.writerow(header)
        for i in range(len(run)):
            out.writerow(
                [int(run.index[i]), *run.commanded[i].tolist(), *run.read_back[i].tolist(),
                 *result.wi[i].tolist(), *result.wo[i].tolist(), float(run.exposure_s[i]),
                 int(run.averages[i]), float(run.value[i]), float(run.std[i]),
                 int(run.saturated[i]), float(result.brdf[i]), float(result.truth[i]),
                 float(run.settled_s[i])]
            )  # fmt: skip


def cmd_simulate(args: argparse.Namespace) -> int:
    if args.output is not None:
        check_output(args.output, "-o")
    source = load_plan_source(args.plan, args.rig)
    scene = load_scene(args.scene, source.rig)
    if args.no_effects:
        scene = scene.with_effects([])
    plan = source.build()
    result = simulate_plan(plan, scene, args.seed)
    print(render(result))
    if args.output is not None:
        write_csv(result, args.output)
        print(f"wrote {len(result.run)} targets to {args.output}")
    return 0
