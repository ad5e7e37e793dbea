"""Adaptive against uniform sampling, noise-free: for each material, the
best uniform plan (over the four parametrizations and the methods, Sobol placed by the
planner: `studies.reconstruct.synthetic`) and the adaptive plan (`sampling: {strategy:
adaptive}`: a Sobol survey, a lambert+beckmann fit of it steering the second pass,
`gonio.planner.two_pass`), each reconstructed without being told the material's family
and scored by log-RMSE on log(1 + f) over the default test set (20 000 pairs uniform
in dωi dωo over what the rig measures, θ ≤ 80°; `extrapolate="nearest"`). Then the
samples each needs for log-RMSE 0.01 (log-log between the counts measured) and the
ratios: adaptive error / best uniform error at equal counts, adaptive samples / best
uniform samples for 0.01. No material below is a Beckmann one: the steering model's
family never contains the scene's (``--model survey`` steers with no model at all).

Run: .venv/bin/python benchmarks/adaptive.py [--scenes ggx0.1 ...] [--targets 500 1000 2000 4000]
[--methods linear rbf] [--survey 128] [--floor 0.2] [--edge 0.0] [--model survey]
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies

import _report
from _machine import describe
from study import fmt_needed, needed

from gonio import brdf, params
from gonio.analysis.measured import Measured
from gonio.reconstruct import testset
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.evaluate import evaluate
from gonio.rig.model import Rig
from gonio.types import BrdfEval
from studies.reconstruct.synthetic import synthesize, synthesize_adaptive

ROOT = Path(__file__).resolve().parent.parent
TARGET = 0.01
SEED = 3


def ggx(alpha: float) -> BrdfEval:
    return brdf.create(
        "cook_torrance", alpha=alpha, distribution="ggx", fresnel="schlick", f0=0.04, kd=0.2
    ).eval


def scene_material(name: str) -> BrdfEval:
    from gonio.radiometry.bands import band_eval
    from sim.scene import load_scene

    return band_eval(
        load_scene(ROOT / "configs/scenes" / f"{name}.yaml").material.model(), "luminance"
    )


#: name → (material, rig file, isotropic, what it is).
SCENES: dict[str, tuple[Callable[[], BrdfEval], str, bool, str]] = {
    "ggx0.1": (lambda: ggx(0.1), "arch", True, "GGX α 0.1, F0 0.04, kd 0.2"),
    "ggx0.05": (lambda: ggx(0.05), "arch", True, "GGX α 0.05, F0 0.04, kd 0.2"),
    "ggx0.3": (lambda: ggx(0.3), "arch", True, "GGX α 0.3, F0 0.04, kd 0.2"),
    "matte": (lambda: scene_material("matte"), "arch", True, "matte scene (GGX α 0.5, kd 0.6)"),
    "brushed": (lambda: scene_material("brushed_metal"), "arch", False,
                "brushed_metal scene (anisotropic GGX 0.05 × 0.25, conductor)"),
    "seed000": (lambda: scene_material("seed000_specular"), "arch_point", True,
                "seed000_specular scene (the test function)"),
}  # fmt: skip


def score(samples: Measured, method: str, truth: BrdfEval, rig: Rig, pairs: testset.TestSet,
          isotropic: bool) -> float:  # fmt: skip
    candidate = reconstruct(samples, method=method, extrapolate="nearest")
    result = evaluate(candidate, truth, rig, isotropic=isotropic, test_set=pairs)
    value = result.regions["all"].scores.log_rmse
    assert value is not None
    return value


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--targets", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    parser.add_argument("--methods", nargs="+", default=["linear", "rbf"])
    parser.add_argument("--adaptive-in", nargs="+", default=["rusinkiewicz", "hybrid"])
    parser.add_argument("--survey", type=int, default=128)
    parser.add_argument("--floor", type=float, default=0.2)
    parser.add_argument("--edge", type=float, default=0.0)
    parser.add_argument(
        "--model",
        default="lambert+beckmann",
        help="the family steering the second pass, or 'survey' (no model)",
    )
    args = parser.parse_args()
    options = {"survey": args.survey, "model": args.model, "floor": args.floor,
               "edge": args.edge}  # fmt: skip
    counts = args.targets
    print(describe())
    steer = "its own rbf reconstruction" if args.model == "survey" else f"a {args.model} fit"
    print(f"log-RMSE on log(1 + f); adaptive: survey {args.survey}, steered by {steer}, "
          f"floor {args.floor}, edge {args.edge}")  # fmt: skip
    summary = []
    for name in args.scenes:
        make, rig_name, isotropic, what = SCENES[name]
        truth = make()
        rig = Rig.from_yaml(ROOT / "configs/rigs" / f"{rig_name}.yaml")
        pairs = testset.draw(rig, isotropic=isotropic)
        print(
            f"\n### {name}: {what}, rig {rig_name}, {'isotropic' if isotropic else 'anisotropic'}\n"
        )
        head = " | ".join(f"{n:,}" for n in counts)
        print(f"| plan | parametrization | method | {head} | for {TARGET} |")
        print("|---|---|---|" + "---:|" * (len(counts) + 1))
        rows: dict[tuple[str, str, str], list[float]] = {}
        for kind, names in (("uniform", params.names()), ("adaptive", args.adaptive_in)):
            for parametrization in names:
                for n in counts:
                    if kind == "uniform":
                        samples = synthesize(truth, rig, parametrization, isotropic, n, seed=SEED)
                    else:
                        samples = synthesize_adaptive(
                            truth, rig, parametrization, isotropic, n, seed=SEED, adaptive=options
                        )
                    for method in args.methods:
                        key = (kind, parametrization, method)
                        rows.setdefault(key, []).append(
                            score(samples, method, truth, rig, pairs, isotropic)
                        )
                for method in args.methods:
                    errors = rows[(kind, parametrization, method)]
                    cells = " | ".join(f"{e:.4f}" for e in errors)
                    reach = fmt_needed(needed(counts, errors, TARGET), counts)
                    print(f"| {kind} | {parametrization} | {method} | {cells} | {reach} |",
                          flush=True)  # fmt: skip
        best = {
            kind: [min(e[i] for k, e in rows.items() if k[0] == kind) for i in range(len(counts))]
            for kind in ("uniform", "adaptive")
        }
        ratios = [u / a for u, a in zip(best["uniform"], best["adaptive"], strict=True)]
        nu, na = (needed(counts, best[k], TARGET) for k in ("uniform", "adaptive"))
        sample_ratio = "n/a" if math.isinf(nu) or math.isinf(na) else f"{na / nu:.2f}"
        print(f"\nbest uniform / best adaptive error at equal counts: "
              f"{', '.join(f'{r:.2f}×' for r in ratios)}; samples for {TARGET}: uniform "
              f"{fmt_needed(nu, counts)}, adaptive {fmt_needed(na, counts)} "
              f"(ratio {sample_ratio})")  # fmt: skip
        summary.append((name, ratios, nu, na, sample_ratio))
    print(f"\n| scene | error ratio at {', '.join(f'{n:,}' for n in counts)} | samples for "
          f"{TARGET}: uniform | adaptive | adaptive / uniform |")  # fmt: skip
    print("|---|---|---:|---:|---:|")
    for name, ratios, nu, na, sample_ratio in summary:
        print(f"| {name} | {', '.join(f'{r:.2f}×' for r in ratios)} | {fmt_needed(nu, counts)} "
              f"| {fmt_needed(na, counts)} | {sample_ratio} |")  # fmt: skip


def variant(argv: Sequence[str]) -> str | None:
    """A run of some scenes, or steered by another model, has its own page:
    adaptive-<scenes>[-<model>].md."""
    parts = [*_report.option(argv, "--scenes"), *_report.option(argv, "--model")]
    return "-".join(p.replace("+", "-") for p in parts) or None


def title(argv: Sequence[str]) -> str:
    scenes, model = _report.option(argv, "--scenes"), _report.option(argv, "--model")
    steered = f", steered by {model[0]}" if model else ""
    where = f": {', '.join(scenes)}{steered}" if scenes or model else ""
    return "Adaptive against uniform sampling" + where


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title=title, variant=variant)
