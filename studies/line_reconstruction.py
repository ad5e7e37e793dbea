"""Reconstruction from line data: what a fly plan's sweeps along θh give each method.

Samples are synthesized (studies.reconstruct.synthetic_lines: no planner, no engine, no
noise): lines along θh from 0 every STEP degrees at fixed (θd, φd) of Rusinkiewicz's
isotropic coordinates, the positions a scrambled Sobol set over [0, 90°] × [0, 180°),
kept where the arch rig reaches the pair, valued by the scene's material as its detector
sees it: the glossy gold (GGX α 0.05, conductor) and the matte paint (GGX α 0.5 plus a
Lambertian part). Each method reconstructs them (log transform, Rusinkiewicz
coordinates) and `gonio.reconstruct.evaluate` scores it as `gonio evaluate` does: every
pair of the default test set (20 000 pairs uniform in dωi dωo over what the rig measures,
θ ≤ 80°, seed 14), those outside the reconstruction's support filled by the nearest
samples; "support" is the share inside it, "inside" the log-RMSE over those pairs only.
`lines` uses the line structure (found from the coordinates), `rbf` stretches θh to the
lines' spacing on such data, `linear` is the Delaunay interpolation of every sample.

Run: .venv/bin/python studies/line_reconstruction.py [--lines 100 300] [--steps 0.5 0.2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report
from _machine import describe

from gonio.radiometry import band_eval
from gonio.reconstruct import DEFAULT_FILL, evaluate, reconstruct, testset
from gonio.rig import Rig
from gonio.scene import load_scene
from gonio.types import BrdfEval
from studies.reconstruct.synthetic_lines import synthesize_lines

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "configs" / "rigs" / "arch.yaml"
SCENES = {"glossy gold": "glossy_metal.yaml", "matte": "matte.yaml"}
METHODS = ("linear", "rbf", "lines")


def scene_f(file: str) -> BrdfEval:
    scene = load_scene(ROOT / "configs" / "scenes" / file)
    return band_eval(scene.material.model(), scene.detector.band)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, nargs="+", default=[100, 300])
    ap.add_argument("--steps", type=float, nargs="+", default=[0.5, 0.2], help="degrees")
    ap.add_argument("--methods", nargs="+", default=list(METHODS))
    args = ap.parse_args()
    print(f"machine: {describe()}\n")
    rig = Rig.from_yaml(RIG)
    pairs = testset.draw(rig, isotropic=True)
    print(
        "| scene | lines | step (°) | samples | method | log-RMSE | support | inside "
        "| mirror log-RMSE | grazing log-RMSE | build (s) | evaluate (s) |"
    )
    print("| --- | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    best: dict[tuple[str, int, float], dict[str, float]] = {}
    for scene, file in SCENES.items():
        f = scene_f(file)
        for lines in args.lines:
            for step in args.steps:
                measured, _ = synthesize_lines(f, rig, lines, step, seed=1)
                for method in args.methods:
                    start = time.perf_counter()
                    r = reconstruct(measured, method=method, extrapolate=DEFAULT_FILL)
                    built = time.perf_counter() - start
                    start = time.perf_counter()
                    result = evaluate(r, f, rig, isotropic=True, test_set=pairs)
                    spent = time.perf_counter() - start
                    inside = evaluate(
                        r, f, rig, isotropic=True, test_set=pairs, only_supported=True
                    )
                    every = result.regions["all"]
                    score = every.scores.log_rmse or float("nan")
                    best.setdefault((scene, lines, step), {})[method] = score
                    print(
                        f"| {scene} | {lines} | {step:g} | {len(measured):,} | {method} | "
                        f"{score:.4g} | {100 * (every.coverage or 0):.1f} % | "
                        f"{inside.regions['all'].scores.log_rmse or float('nan'):.4g} | "
                        f"{result.regions['mirror'].scores.log_rmse or float('nan'):.4g} | "
                        f"{result.regions['grazing'].scores.log_rmse or float('nan'):.4g} | "
                        f"{built:.2f} | {spent:.2f} |",
                        flush=True,
                    )
    print("\nlog-RMSE of linear and rbf over that of lines (above 1: lines is better):\n")
    print("| scene | lines | step (°) | linear / lines | rbf / lines |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for (scene, lines, step), scores in best.items():
        if {"lines", "linear", "rbf"} <= set(scores):
            ratio = [scores[m] / scores["lines"] for m in ("linear", "rbf")]
            print(f"| {scene} | {lines} | {step:g} | {ratio[0]:.2f} | {ratio[1]:.2f} |")


if __name__ == "__main__":
    _report.run(
        main, __file__, __doc__, title="Reconstruction from line data (fly sweeps along θh)"
    )
