"""Reconstruction: build time and evaluation throughput of each method, and the study
that chose the default transform (docs/explanations/reconstruction.md).

Samples are synthesized (studies.reconstruct.synthetic: uniform Sobol coordinates of the
plan's parametrization, or a grid, kept where the arch rig reaches, valued by the
matte scene's material) — no engine run. Throughput counts pairs through
`Reconstruction.evaluate` (value, σ and the support mask, the rig's reachability
included) on pairs the rig reaches; the last column takes out the time of
`Rig.reachable` on the supported pairs, measured alone right after. Targets (2-core
machine): build < 2 s and ≥ 500 000 pairs/s for linear and grid at 20 000 samples.
Run: .venv/bin/python benchmarks/reconstruct.py [--sizes 5000 20000] [--pairs 200000]
     .venv/bin/python benchmarks/reconstruct.py --transforms
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report
from _machine import describe

from gonio.reconstruct import transforms
from gonio.reconstruct.build import reconstruct
from gonio.rig.model import Rig
from gonio.types import BrdfEval
from studies.reconstruct.synthetic import placed, synthesize

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "configs" / "rigs" / "arch.yaml"
SCENES = ROOT / "configs" / "scenes"


def scene_f(name: str) -> BrdfEval:
    from gonio.radiometry.bands import band_eval
    from sim.scene import load_scene

    scene = load_scene(SCENES / f"{name}.yaml")
    return band_eval(scene.material.model(), scene.detector.band)


def grid_per_axis(rig: Rig, parametrization: str, isotropic: bool, n: int) -> int:
    """Nodes per axis giving about ``n`` kept grid cells."""
    d = 3 if isotropic else 4
    probe = 12 if isotropic else 8
    kept = len(placed(rig, parametrization, isotropic, 0, grid=probe)[0]) / probe**d
    return max(2, round((n / kept) ** (1.0 / d)))


def timing(args: argparse.Namespace) -> None:
    rig = Rig.from_yaml(RIG)
    f = scene_f("matte")
    print(
        "| samples | coordinates | method | samples used | build (s) | eval (pairs/s) "
        "| eval less the rig's check (pairs/s) |"
    )
    print("| ---: | --- | --- | ---: | ---: | ---: | ---: |")
    caps = {}
    for isotropic in (True, False):
        queries = placed(rig, "hybrid", isotropic, args.pairs, seed=11)
        start = time.perf_counter()
        rig.reachable(*queries, isotropic=isotropic)
        caps[isotropic] = len(queries[0]) / (time.perf_counter() - start)
        for n in args.sizes:
            for method in ("linear", "grid", "rbf"):
                grid = grid_per_axis(rig, "hybrid", isotropic, n) if method == "grid" else None
                measured = synthesize(f, rig, "hybrid", isotropic, n, grid=grid)
                start = time.perf_counter()
                r = reconstruct(measured, method=method)
                built = time.perf_counter() - start
                pairs = (
                    queries if method != "rbf" else tuple(q[: args.pairs // 20] for q in queries)
                )
                start = time.perf_counter()
                _, _, ok = r.evaluate(*pairs)
                spent = time.perf_counter() - start
                rate = len(pairs[0]) / spent
                # The rig's check, as the evaluation ran it (on the otherwise supported pairs;
                # ok is a subset of those).
                start = time.perf_counter()
                rig.reachable(pairs[0][ok], pairs[1][ok], isotropic=isotropic)
                rest = len(pairs[0]) / max(spent - (time.perf_counter() - start), 1e-9)
                kind = "isotropic (3)" if isotropic else "anisotropic (4)"
                print(
                    f"| {n:,} | {kind} | {method} | {len(measured):,} | {built:.2f} | "
                    f"{rate:,.0f} | {rest:,.0f} |",
                    flush=True,
                )
    print(
        f"\nrig.reachable alone on the same pairs (part of every evaluation): "
        f"{caps[True]:,.0f} pairs/s isotropic, {caps[False]:,.0f} anisotropic"
    )


def study(args: argparse.Namespace) -> None:
    """Relative error of linear reconstructions of each scene's material per transform."""
    rig = Rig.from_yaml(RIG)
    print("| scene | coordinates | transform | median rel. error | 95th pct | RMS log error |")
    print("| --- | --- | --- | ---: | ---: | ---: |")
    for scene, isotropic in (
        ("matte", True),
        ("glossy_metal", True),
        ("brushed_metal", False),
        ("seed000_specular", True),
    ):
        f = scene_f(scene)
        measured = synthesize(f, rig, "hybrid", isotropic, args.study_samples)
        wi, wo = placed(rig, "hybrid", isotropic, 20_000, seed=7)
        truth = f(wi, wo)
        for name in transforms.TRANSFORMS:
            value, _, ok = reconstruct(measured, transform=name).evaluate(wi, wo)
            t, v = truth[ok], np.maximum(value[ok], 0.0)
            rel = np.abs(v - t) / np.maximum(t, 1e-3)
            log = np.log((v + 1e-3) / (t + 1e-3))
            kind = "isotropic" if isotropic else "anisotropic"
            print(
                f"| {scene} | hybrid {kind} | {name} | {np.median(rel):.2e} | "
                f"{np.percentile(rel, 95):.2e} | {np.sqrt(np.mean(log**2)):.2e} |"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[5_000, 20_000])
    ap.add_argument("--pairs", type=int, default=200_000)
    ap.add_argument("--transforms", action="store_true", help="run the transform study")
    ap.add_argument("--study-samples", type=int, default=3_000)
    args = ap.parse_args()
    print(f"machine: {describe()}\n")
    if args.transforms:
        study(args)
    else:
        timing(args)


def transform_page(argv: Sequence[str]) -> str | None:
    """The transform study has its own page: reconstruct-transforms.md."""
    return "transforms" if "--transforms" in argv else None


if __name__ == "__main__":
    _report.run(
        main,
        __file__,
        __doc__,
        title=lambda argv: (
            "Reconstruction: the study that chose the default transform"
            if transform_page(argv)
            else "Reconstruction: build time and evaluation throughput"
        ),
        variant=transform_page,
    )
