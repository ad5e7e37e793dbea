"""The bias a misaligned rig leaves in the recovered BRDF: each parameter of the scene's
``misalignment`` effect alone, at a few sizes, on the arch rig measuring the glossy
metal and the matte scene (their noise and effects on) with a uniform plan through the
acquisition engine, calibrated against the reference standard as on hardware (the
standard sits on the same misaligned stage), recorded with the rig file's angles and
directions. Each row is scored against the scene's material at the rig file's pairs
(what a user of the run would compare): the log-RMSE over the calibrated samples, the
signed median log ratio, and the log-RMSE over the default test set of the naive
reconstruction (`gonio.reconstruct.evaluate`, all pairs and the mirror region). Every
run has the same seed, so the aligned row's noise and reconstruction error are in every
row and what a row adds to it is the misalignment's. The height is also shown on the
arch rig with a point source 300 mm away (the matte material), where it turns ωi.

A light's or a detector's pointing error about its last axis (y) is that axis's zero
offset (`gonio.rig.alignment`), so only the turn about x (out of its plane) is shown.
With a collimated beam and a distant detector a height only shifts the spots, which
the simulator does not apply (the footprint stays centred): its rows there equal the
aligned one by construction. With a collimated beam whose spot the detector sees whole
a reading is f cos θo (`gonio.radiometry.relative_geometry`), so an error δ in the
detector's elevation biases even a Lambertian reading by about tan θo · δ, the reference
standard's at θo = 45° among them (a point source's reading carries cos θi instead).

Run: .venv/bin/python studies/misalignment.py [--targets 600]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import numpy as np
from _machine import describe

from gonio.analysis import Measured, truth_of
from gonio.planner import PlanSpec, build
from gonio.reconstruct import NaiveReconstruction, evaluate, testset, truth_from_spec
from gonio.rig import Rig
from gonio.scene import Scene, load_scene
from gonio.workflows import simulate_plan

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"glossy metal": "glossy_metal.yaml", "matte": "matte.yaml"}
#: A point source's intensity (W/sr) giving the collimated scenes' 1 W/m² at 300 mm.
POINT_INTENSITY = 0.09


def cases(rig: Rig) -> list[tuple[str, dict[str, Any]]]:
    """(label, misalignment) of every row: aligned, then each parameter alone."""
    out: list[tuple[str, dict[str, Any]]] = [("aligned", {})]
    for axis in rig.axes:
        for size in (0.1, 0.3, 1.0):
            out.append((f"zero {axis} {size}°", {"zero_offset_deg": {axis: size}}))
    for size in (0.1, 0.5):
        out.append((f"tilt {size}°", {"tilt_deg": size, "tilt_azimuth_deg": 30.0}))
    for size in (0.1, 0.5):
        out.append((f"height {size} mm", {"height_mm": size}))
    for chain in ("light", "detector"):
        for size in (0.1, 0.3):
            out.append((f"{chain} pointing {size}°", {f"{chain}_pointing_deg": (size, 0.0)}))
    return out


def plan_spec(targets: int) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": f"misalignment-{targets}",
            "parametrization": "hybrid",
            "isotropic": True,
            "sampling": {"strategy": "sobol", "target": targets, "seed": 3},
            "exposure": {"seconds": 0.05, "averages": 1},
            "time_budget_s": 3600,
            "acquisition": {"calibration": {"every_samples": 500, "dark": True, "averages": 16}},
        }
    )


def score(rig: Rig, scene: Scene, targets: int, pairs: Any) -> tuple[float, ...]:
    """(samples log-RMSE, median log ratio, test-set log-RMSE all, mirror) of one run."""
    result = simulate_plan(build(plan_spec(targets), rig), scene)
    truth = truth_of(result.run)  # at the rig file's pairs
    ok = (result.brdf > 0) & (truth > 0) & np.isfinite(result.brdf)
    ratio = np.log(result.brdf[ok] / truth[ok])
    m = Measured.from_run(result.run, result.calibrated)
    e = evaluate(
        NaiveReconstruction(m), truth_from_spec(None, m), rig, isotropic=True, test_set=pairs
    )
    return (
        float(np.sqrt(np.mean(ratio**2))),
        float(np.median(ratio)),
        e.regions["all"].scores.log_rmse or 0.0,
        e.regions["mirror"].scores.log_rmse or 0.0,
    )


def table(
    label: str, rig: Rig, base: Scene, rows: list[tuple[str, dict[str, Any]]], targets: int
) -> None:
    pairs = testset.draw(rig, isotropic=True)
    print(f"\n**{label}** ({targets} targets, {len(pairs)} test pairs)\n")
    print(
        "| misalignment | samples log-RMSE | Δ vs aligned | median log ratio | "
        "test log-RMSE | Δ | mirror log-RMSE | Δ |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    aligned: tuple[float, ...] | None = None
    effects = base.effects.model_dump()
    for name, spec in rows:
        scene = base.with_effects({**effects, "misalignment": spec} if spec else effects)
        s = score(rig, scene, targets, pairs)
        aligned = s if aligned is None else aligned
        print(
            f"| {name} | {s[0]:.4f} | {s[0] - aligned[0]:+.4f} | {s[1]:+.4f} | {s[2]:.4f} | "
            f"{s[2] - aligned[2]:+.4f} | {s[3]:.4f} | {s[3] - aligned[3]:+.4f} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", type=int, default=600)
    args = parser.parse_args()
    print(describe())
    started = time.perf_counter()
    arch = Rig.from_yaml(ROOT / "configs/rigs/arch.yaml")
    for label, file in SCENES.items():
        table(
            f"{label}, arch rig",
            arch,
            load_scene(ROOT / "configs/scenes" / file),
            cases(arch),
            args.targets,
        )
    point = Rig.from_yaml(ROOT / "configs/rigs/arch_point.yaml")
    matte = load_scene(ROOT / "configs/scenes/matte.yaml")
    lamp = Scene.model_validate(
        {**matte.model_dump(), "source": {"intensity_w_sr": POINT_INTENSITY}}
    )
    heights = [(n, s) for n, s in cases(point) if n == "aligned" or n.startswith("height")]
    heights.append(("height 2.0 mm", {"height_mm": 2.0}))
    table("matte, arch rig with a point source at 300 mm", point, lamp, heights, args.targets)
    print(f"\nall runs: {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="What a misaligned rig does to the BRDF")
