"""Reconstruction: build time and evaluation throughput of each method, and the study
that chose the default transform (docs/explanations/reconstruction.md).

Samples are synthesized (studies.reconstruct.synthetic: uniform Sobol coordinates of the
plan's parametrization, or a grid, kept where the arch rig reaches, valued by the
matte scene's material) — no engine run. Throughput counts pairs through
`Reconstruction.evaluate` (value, σ and the support mask, the rig's reachability
included) on pairs the rig reaches; the last column takes out the time of
`Rig.reachable` on the supported pairs, measured alone right after. Targets (2-core
machine): build < 2 s and ≥ 500 000 pairs/s for linear and grid at 20 000 samples.

Then linear evaluation against the number of pairs: the isotropic reconstruction of the
largest sample count evaluated on 10⁴, 10⁵ and 10⁶ pairs the rig reaches, beside
scipy's `LinearNDInterpolator` built on the same samples' scaled coordinates and called
on the same pairs' scaled coordinates (scipy's call alone: a first call, not timed,
computes its barycentric transforms; gonio's evaluation includes the coordinates, σ,
the support mask and the rig's check). Each size is called repeatedly, up to 10⁶ pairs a
run, so that every rate is measured over a like stretch of time on the shared machine;
two runs of each, interleaved with scipy's, the better counts. The target is a rate at
10⁶ pairs at least that at 10⁴ and at least scipy's at every size, the goal 500 000
pairs/s. Last, where an evaluation of 10⁶ pairs spends its CPU time: each step alone on
the same blocks of pairs as the evaluation (the nearest-sample search runs on both
cores).
Run: .venv/bin/python benchmarks/reconstruct.py [--sizes 5000 20000] [--pairs 200000]
     [--scaling 10000 100000 1000000]
     .venv/bin/python benchmarks/reconstruct.py --transforms
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report
from _machine import describe
from scipy.interpolate import LinearNDInterpolator

from gonio.blocks import blockwise
from gonio.reconstruct import EVALUATION_BLOCK, Reconstruction, reconstruct, transforms
from gonio.rig import Rig
from gonio.types import BrdfEval, FloatArray
from studies.reconstruct.synthetic import placed, synthesize

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "configs" / "rigs" / "arch.yaml"
SCENES = ROOT / "configs" / "scenes"
#: The evaluation rate the project aims at (pairs/s).
GOAL = 500_000
#: Runs of each timing (the better counts).
RUNS = 2


def scene_f(name: str) -> BrdfEval:
    from gonio.radiometry import band_eval
    from gonio.scene import load_scene

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
    scaling(rig, f, max(args.sizes), args.scaling)


def reached(rig: Rig, n: int) -> tuple[FloatArray, FloatArray]:
    """``n`` pairs the rig reaches (isotropic hybrid Sobol plans of up to a million
    targets, one seed after another)."""
    parts: list[tuple[FloatArray, FloatArray]] = []
    seed = 11
    while sum(len(p[0]) for p in parts) < n:
        parts.append(placed(rig, "hybrid", True, min(n, 1_000_000), seed=seed))
        seed += 1
    wi = np.concatenate([p[0] for p in parts])[:n]
    wo = np.concatenate([p[1] for p in parts])[:n]
    return wi, wo


def timed(calls: int, fn: Callable[[], object]) -> tuple[float, float]:
    """The wall time and the CPU time (s) of ``calls`` calls of ``fn`` in a row."""
    start, start_cpu = time.perf_counter(), time.process_time()
    for _ in range(calls):
        fn()
    return time.perf_counter() - start, time.process_time() - start_cpu


def scaling(rig: Rig, f: BrdfEval, samples: int, sizes: Sequence[int]) -> None:
    """Linear evaluation at each number of pairs, beside scipy's LinearNDInterpolator."""
    measured = synthesize(f, rig, "hybrid", True, samples)
    r = reconstruct(measured, method="linear")
    x = r.space.scaled(measured.wi, measured.wo)
    scipy_linear = LinearNDInterpolator(x, np.log(measured.f.reshape(len(x), -1)))
    queries = reached(rig, max(sizes))
    scipy_linear(r.space.scaled(queries[0][:10], queries[1][:10]))  # its transforms
    r.evaluate(queries[0][:10], queries[1][:10])
    print(
        f"\n== Linear evaluation against the number of pairs ({samples:,} samples, "
        "isotropic hybrid)\n"
    )
    print(
        "| pairs | gonio (pairs/s) | gonio (pairs per CPU second) | scipy LinearNDInterpolator "
        f"(pairs/s) | gonio / scipy | gonio / goal ({GOAL:,}) |"
    )
    print("| ---: | ---: | ---: | ---: | ---: | ---: |")
    rates = {}
    for n in sizes:
        wi, wo = queries[0][:n], queries[1][:n]
        scaled = r.space.scaled(wi, wo)
        calls = max(1, max(sizes) // n)
        ours, cpu, theirs = (float("inf"),) * 3
        for _ in range(RUNS):  # interleaved: both see the same load
            wall, used = timed(calls, lambda wi=wi, wo=wo: r.evaluate(wi, wo))
            ours, cpu = min(ours, wall), min(cpu, used)
            theirs = min(theirs, timed(calls, lambda s=scaled: scipy_linear(s))[0])
        rates[n] = rate = n * calls / ours
        print(
            f"| {n:,} | {rate:,.0f} | {n * calls / cpu:,.0f} | {n * calls / theirs:,.0f} | "
            f"{theirs / ours:.2f} | {rate / GOAL:.2f} |",
            flush=True,
        )
    low, high = min(sizes), max(sizes)
    print(
        f"\nAt {high:,} pairs the evaluation runs at {rates[high] / rates[low]:.2f} times its "
        f"rate at {low:,} pairs, {rates[high] / GOAL:.0%} of the goal of {GOAL:,} pairs/s."
    )
    breakdown(r, rig, queries[0][:high], queries[1][:high])


def breakdown(r: Reconstruction, rig: Rig, wi: FloatArray, wo: FloatArray) -> None:
    """CPU time per pair of each step of an evaluation, alone on the evaluation's blocks."""
    n = len(wi)
    x = blockwise(r.space.scaled, wi, wo, size=EVALUATION_BLOCK)
    distance, nearest = blockwise(r.domain.nearest, x, size=EVALUATION_BLOCK)
    # The pairs near a sample, in the order of their nearest sample (as the evaluation
    # takes them in each block).
    near = np.flatnonzero(np.isfinite(distance))
    near = near[np.argsort(nearest[near], kind="stable")]
    x_near, nearest_near = x[near], nearest[near]
    steps = {
        "coordinates (Space.scaled)": lambda: blockwise(
            r.space.scaled, wi, wo, size=EVALUATION_BLOCK
        ),
        "nearest-sample search (cKDTree)": lambda: blockwise(
            r.domain.nearest, x, size=EVALUATION_BLOCK
        ),
        "walk and interpolation (Linear)": lambda: blockwise(
            r.interpolant, x_near, nearest_near, size=EVALUATION_BLOCK
        ),
        "the rig's check (Rig.reachable)": lambda: rig.reachable(wi, wo, isotropic=True),
    }
    whole = min(timed(1, lambda: r.evaluate(wi, wo))[1] for _ in range(RUNS))
    print(f"\n== Where an evaluation of {n:,} pairs spends its CPU time\n")
    print("| step | ns per pair | share |")
    print("| --- | ---: | ---: |")
    spent = 0.0
    for label, fn in steps.items():
        cpu = min(timed(1, fn)[1] for _ in range(RUNS))
        spent += cpu
        print(f"| {label} | {cpu / n * 1e9:,.0f} | {cpu / whole:.0%} |")
    rest = whole - spent
    label = "the rest (support, seams, transform, σ)"
    print(f"| {label} | {rest / n * 1e9:,.0f} | {rest / whole:.0%} |")
    print(f"| the whole evaluation | {whole / n * 1e9:,.0f} | 100% |")


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
    ap.add_argument(
        "--scaling",
        type=int,
        nargs="+",
        default=[10_000, 100_000, 1_000_000],
        help="numbers of pairs of the linear evaluation's scaling table",
    )
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
