"""Fits of simulated runs over independent seeds.

For each scene, one run per seed (a separate simulated acquisition: its own noise and
its own reference readings; RGB: three runs, one per band, each its own seed) of
``--samples`` targets, fitted by the scene's family with the shared calibration
errors. Prints per parameter the fraction of seeds whose ±2σ interval holds the
scene's value (target ≥ 0.9), the RMS of the z-scores (1 when the errors are right)
and the median reduced χ²; then χ²_red of Beckmann data fitted by other families.
The tests (tests/gonio/reconstruct/test_fit.py) use interleaved subsets of one long
run instead, to stay fast.

Run: .venv/bin/python studies/fit.py [--seeds 20] [--samples 150]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import numpy as np
from _machine import describe

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.support

from gonio.analysis import Measured, shared_error
from gonio.reconstruct import FitResult, fit
from tests.support.runs import plan_spec, scene_spec, simulated_run

NOISE = ["shot_noise", "read_noise"]
#: The glossy metal scene's own material (GGX α = 0.05, gold's complex index per channel).
GOLD = scene_spec("glossy_metal")["material"]
BECKMANN = {"name": "cook_torrance", "alpha": 0.2, "distribution": "beckmann", "f0": 0.9}


def plan(samples: int, isotropic: bool = True) -> dict[str, Any]:
    spec = plan_spec(samples, isotropic=isotropic) | {"max_moves": 0, "kicks": 0}
    spec["acquisition"]["calibration"].update(averages=64)
    return spec


def measured(folder: Path, plan_: dict[str, Any], scene: dict[str, Any]) -> tuple[Any, Any]:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        run = simulated_run(folder, plan_, scene)
    return Measured.from_run(run), shared_error(run)


def table(rows: list[tuple[str, str, list[FitResult], dict[str, float]]]) -> None:
    print("| scene | SPEC | parameter | 2σ coverage | RMS z | median χ²_red |")
    print("|---|---|---|---|---|---|")
    for scene, spec, fits, truth in rows:
        z = np.array(
            [[(r.params()[n][0] - v) / r.params()[n][1] for n, v in truth.items()] for r in fits]
        )
        chi2 = float(np.median([r.chi2_red for r in fits]))
        for j, name in enumerate(truth):
            cover = float(np.mean(np.abs(z[:, j]) <= 2.0))
            rms = float(np.sqrt(np.mean(z[:, j] ** 2)))
            print(f"| {scene} | `{spec}` | {name} | {cover:.2f} | {rms:.2f} | {chi2:.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--samples", type=int, default=150)
    args = parser.parse_args()
    print(describe())
    seeds = range(args.seeds)
    start = time.process_time()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rows = []
        spec = "lambert+ggx"
        fits = []
        for s in seeds:
            m, e = measured(folder, plan(args.samples), scene_spec("matte", effects=NOISE, seed=s))
            fits.append(fit(m, spec, shared=e))
        rows.append(
            ("matte", spec, fits, {"lambert.albedo": 0.6, "ggx.alpha": 0.5, "ggx.f0": 0.04})
        )

        spec = "ggx:fresnel=conductor"
        fits = []
        for s in seeds:
            parts = [
                measured(
                    folder,
                    plan(args.samples),
                    scene_spec(
                        "glossy_metal", material=GOLD, effects=NOISE, band=b, seed=100 + 3 * s + j
                    ),
                )
                for j, b in enumerate("rgb")
            ]
            rgb = Measured.rgb(*(p[0] for p in parts))
            fits.append(fit(rgb, spec, shared=[p[1] for p in parts]))
        truth = {"ggx.alpha": GOLD["alpha"]}
        for j, c in enumerate("rgb"):
            truth |= {f"ggx.ior[{c}]": GOLD["ior"][j], f"ggx.k[{c}]": GOLD["k"][j]}
        rows.append(("gold, RGB", spec, fits, truth))

        spec = "ggx_anisotropic:fresnel=conductor,ior=1.2,k=7"
        fits = []
        for s in seeds:
            scene = scene_spec("brushed_metal", effects=NOISE, seed=200 + s)
            m, e = measured(folder, plan(args.samples, isotropic=False), scene)
            fits.append(fit(m, spec, shared=e))
        truth = {"ggx_anisotropic.alpha_x": 0.05, "ggx_anisotropic.alpha_y": 0.25}
        rows.append(("brushed", spec, fits, truth))
        table(rows)

        m, _ = measured(
            folder, plan(200), scene_spec("glossy_metal", material=BECKMANN, effects=NOISE, seed=5)
        )
        print()
        print("| Beckmann data (α 0.2, f0 0.9, 200 samples) fitted by | χ²_red |")
        print("|---|---|")
        for family in ("beckmann", "ggx", "blinn_phong", "phong", "lambert+phong"):
            print(f"| `{family}` | {fit(m, family).chi2_red:.3g} |")
    print(f"\nCPU {time.process_time() - start:.1f} s")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Fits of simulated runs over independent seeds")
