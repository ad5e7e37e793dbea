"""`gonio simulate PLAN.yaml --scene SCENE.yaml`: measure a plan on the simulated rig.

The plan is measured target by target through the driver protocols (`SimMotorBus`,
`SimDetector`: what the acquisition engine will drive); the reference standard is read
at the 0°/45° geometry before and after (its exposure halved until it does not
saturate), with a dark frame; the readings are carried back to BRDF values through the
calibration, the source's drift divided out by interpolating the two reference readings
in time, with directions recomputed from the read-back motor angles. The summary says
how long the real rig would take, how long the simulation took, and how far the
recovered BRDF is from the scene's model at the pairs measured: what a plan and a set
of effects cost in accuracy, before any hardware moves.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from gonio import radiometry
from gonio.config import check_output
from gonio.errors import GonioError
from gonio.planner.plan import Plan, hms, load_plan_source
from gonio.rig.model import Reason, Rig
from gonio.types import FloatArray
from sim.devices.instrument import SimulatedInstrument
from sim.physics.optics import SceneOptics
from sim.record import SimRun
from sim.scene import Scene, load_scene

#: The calibration geometry: light at the normal, detector 45° away (the classic 0°/45°).
REFERENCE_GEOMETRY_DEG = (0.0, 45.0)


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "simulate",
        help="measure a plan on the simulated rig and compare with the scene's truth",
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


@dataclass(frozen=True)
class Result:
    """A simulated run with its calibration and the BRDF it recovers."""

    plan: Plan
    scene: Scene
    run: SimRun
    wall_s: float
    reference_counts: float  # the first reading of the reference standard
    reference_exposure_s: float
    reference_change: float  # last / first reference signal rate − 1 (the drift seen)
    dark_rate: float  # counts/s with the light off
    brdf: FloatArray  # recovered at the read-back pairs
    truth: FloatArray  # the scene's model at the pairs actually measured
    wi: FloatArray  # from the read-back angles
    wo: FloatArray


def reference_pose(rig: Rig) -> FloatArray:
    """Joint angles of the 0°/45° calibration geometry on ``rig``."""
    ti, to = (math.radians(a) for a in REFERENCE_GEOMETRY_DEG)
    wi = np.array([[math.sin(ti), 0.0, math.cos(ti)]])
    wo = np.array([[-math.sin(to), 0.0, math.cos(to)]])
    solution = rig.solve(wi, wo)
    if solution.reasons[0] not in (Reason.OK, Reason.BLIND_SPOT, Reason.FOOTPRINT):
        raise GonioError(f"rig {rig.spec.name!r} cannot reach the 0°/45° reference geometry")
    return np.asarray(solution.angles[0], dtype=np.float64)


def _reference(
    inst: SimulatedInstrument, k: int, pose: list[float], exposure: float, shortest: float
) -> tuple[float, float]:
    """(counts, exposure s) of the reference standard, the exposure halved until the
    reading does not saturate; `GonioError` if even ``shortest`` saturates."""
    while True:
        reading = inst.measure_reference(k, pose, exposure)
        if not reading.saturated:
            return reading.value, exposure
        if exposure <= shortest:
            raise GonioError(
                f"the reference standard saturates the detector even at {shortest:g} s: "
                "lower the source's power or the detector's aperture"
            )
        exposure = max(exposure / 2, shortest)


def simulate_plan(plan: Plan, scene: Scene, seed: int | None = None) -> Result:
    """Measure ``plan`` in ``scene`` and recover the BRDF (see the module docstring)."""
    rig = plan.rig
    shortest, longest = scene.detector.exposure_range_s
    exposure = float(np.clip(np.median(plan.exposure_s), shortest, longest))
    started = time.perf_counter()
    with SimulatedInstrument(scene, rig, seed=seed) as inst:
        pose = reference_pose(rig).tolist()
        first, exposure = _reference(inst, 0, pose, exposure, shortest)
        t_first = inst.clock.now - exposure / 2  # the middle of the exposure
        inst.light.off()
        dark = inst.measure_reference(1, pose, exposure).value
        inst.light.on()
        run = inst.run(plan)
        last = inst.measure_reference(2, pose, exposure).value
        t_last = inst.clock.now - exposure / 2
    wall = time.perf_counter() - started
    dark_rate = dark / exposure
    wi_ref, wo_ref = rig.forward(np.asarray(pose))
    kind: Literal["collimated", "point"] = scene.source.kind
    calibration = radiometry.ReferenceCalibration.from_counts(
        scene.reference.albedo, first, exposure, wi_ref, wo_ref, kind, dark_counts=dark
    )
    wi, wo = rig.forward(run.read_back)  # directions come from the read-back angles
    recovered = calibration.brdf_from_counts(
        run.value, run.exposure_s, wi, wo, dark_counts=dark_rate * run.exposure_s
    )
    # The source drifts: scale by the reference's rate interpolated to each target.
    change = (last - dark) / (first - dark) - 1.0
    middle = (run.settled_s + run.end_s) / 2  # of each target's exposures
    when = (middle - t_first) / (t_last - t_first)
    recovered = recovered / (1.0 + change * when)
    truth = SceneOptics(scene).models["sample"](run.wi, run.wo)
    return Result(
        plan, scene, run, wall, first, exposure, change, dark_rate, recovered, truth, wi, wo
    )


def render(result: Result) -> str:
    run, plan, scene = result.run, result.plan, result.scene
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
        f"(albedo {scene.reference.albedo:g}, 0°/45°, {result.reference_exposure_s:g} s; "
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
    lines += _point_source_note(result) + _size_note(result)
    return "\n".join(lines)


def _size_note(result: Result) -> list[str]:
    """The rig file's sizes decide what the plan refuses; the scene's, what is measured."""
    scene, c = result.scene, result.plan.rig.spec.constraints
    pairs = [
        ("sample diameter", scene.sample.diameter_mm, c.sample_diameter_mm),
        ("field of view", scene.detector.fov_diameter_mm, c.detector_fov_mm),
    ]
    if scene.source.kind == "collimated":
        pairs.append(("beam diameter", scene.source.beam_diameter_mm, c.beam_diameter_mm))
    differ = [f"{name} {a:g} mm (rig {b:g} mm)" for name, a, b in pairs if a != b]
    if not differ:
        return []
    return [
        f"  note: the scene's {', '.join(differ)} differ from the rig file's, which the "
        "plan's footprint refusals used"
    ]


def _point_source_note(result: Result) -> list[str]:
    """A point source's ideal chain assumes the detector's spot lies on the sample."""
    scene = result.scene
    if scene.source.kind != "point" or scene.effects.footprint is not None:
        return []
    fov, sample = scene.detector.fov_diameter_mm, scene.sample.diameter_mm
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
    scene = load_scene(args.scene)
    if args.no_effects:
        scene = scene.with_effects([])
    plan = source.build()
    result = simulate_plan(plan, scene, args.seed)
    print(render(result))
    if args.output is not None:
        write_csv(result, args.output)
        print(f"wrote {len(result.run)} targets to {args.output}")
    return 0
