"""How the σs of the survey steer an adaptive plan (docs/explanations/adaptive.md
"The steering fit's weights"), noise-free: the second pass follows a lambert+beckmann fit of
the survey, weighted by the survey's σs, so the σ model decides what the fit gets right.

For each material, count and Sobol seed: the best uniform plan's error (Rusinkiewicz,
rbf) over the adaptive plan's (Rusinkiewicz, rbf), the survey's σ either

    relative   σ = 1 % of f (the synthetic default: every value weighted alike in
               relative terms, the tails as much as the peak)
    log1p      σ = 1 % of (1 + f): residuals weighted as in the metric, log(1 + f)
               (absolute where f ≪ 1, relative on the peak)

and the geometric mean over the seeds; then the fit each σ model gives of the first
seed's 128-target survey. The engine's runs use the detector's own σ.

Run: .venv/bin/python studies/adaptive_weights.py [--scenes ggx0.1 glossy_metal ...]
[--counts 500 1000 4000] [--seeds 3 4 5]   (about 5 minutes per scene on one core)
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies

import _report
from _machine import describe
from adaptive import ggx
from study import score, setting

from gonio.reconstruct import fit
from gonio.rig import Rig
from gonio.types import BrdfEval
from studies.reconstruct.synthetic import synthesize, synthesize_adaptive

ROOT = Path(__file__).resolve().parent.parent
#: σ model → the absolute part of σ = 1 % × (|f| + floor), in sr⁻¹.
FLOORS = {"relative": 0.0, "log1p": 1.0}


def material(name: str) -> tuple[Rig, bool, BrdfEval]:
    """``ggx<α>`` (F0 0.04 over kd 0.2, arch rig) or a shipped scene's stem."""
    if name.startswith("ggx"):
        return Rig.from_yaml(ROOT / "configs/rigs/arch.yaml"), True, ggx(float(name[3:]))
    return setting(name)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "--scenes",
        nargs="+",
        default=["ggx0.1", "ggx0.05", "ggx0.3", "glossy_metal", "matte", "seed000_specular"],
    )
    parser.add_argument("--counts", type=int, nargs="*", default=[500, 1000, 4000])
    parser.add_argument("--seeds", type=int, nargs="+", default=[3, 4, 5])
    args = parser.parse_args()
    print(describe())
    print("\nbest uniform / adaptive error (Rusinkiewicz, rbf), per seed; geometric mean\n")
    print(
        "| material | samples | σ of the survey | "
        + " | ".join(f"seed {s}" for s in args.seeds)
        + " | mean |"
    )
    print("|---|---:|---|" + "---:|" * (len(args.seeds) + 1))
    for name in args.scenes:
        rig, iso, truth = material(name)
        for n in args.counts:
            uniform = [
                score(
                    synthesize(truth, rig, "rusinkiewicz", iso, n, seed=s), "rbf", truth, rig, iso
                )["log_rmse"]
                for s in args.seeds
            ]
            for label, floor in FLOORS.items():
                ratios = []
                for s, u in zip(args.seeds, uniform, strict=True):
                    plan = synthesize_adaptive(
                        truth, rig, "rusinkiewicz", iso, n, seed=s, sigma_floor=floor
                    )
                    ratios.append(u / score(plan, "rbf", truth, rig, iso)["log_rmse"])
                mean = math.exp(sum(math.log(r) for r in ratios) / len(ratios))
                cells = " | ".join(f"{r:.2f}×" for r in ratios)
                print(f"| {name} | {n:,} | {label} | {cells} | {mean:.2f}× |", flush=True)
    print(f"\nThe steering fit (lambert+beckmann) of the seed-{args.seeds[0]} survey\n")
    print("| material | σ of the survey | fitted parameters |")
    print("|---|---|---|")
    for name in args.scenes:
        rig, iso, truth = material(name)
        for label, floor in FLOORS.items():
            survey = synthesize(
                truth, rig, "rusinkiewicz", iso, 128, seed=args.seeds[0], sigma_floor=floor
            )
            result = fit(survey, "lambert+beckmann")
            values = ", ".join(
                f"{k} {v:.3g}" for k, v in zip(result.names, result.values, strict=True)
            )
            print(f"| {name} | {label} | {values} |", flush=True)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The steering fit's weights")
