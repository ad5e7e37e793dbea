"""The reconstruction against the naive reference: noise-free samples of
uniform Sobol plans (`studies.reconstruct.synthetic`) of GGX α = 0.05, 0.1, 0.3 with F0 = 0.04
(Schlick) over a Lambertian base kd = 0.2, on the arch rig (θ ≤ 80°), in each
parametrization; each method scored by log-RMSE on log(1 + f) over the default test set
(`gonio.reconstruct.testset`, 20 000 pairs uniform in solid angle over what the rig
measures). Every method answers every pair: the naive grid fills by its nearest node, the
others by `extrapolate="nearest"`. Then the sample count each (parametrization, method)
needs for log-RMSE 0.01, interpolated log-log between the counts measured.

Run: .venv/bin/python studies/accuracy.py [--alphas 0.05 0.1 0.3]
[--targets 500 1000 2000 5000 10000 30000] [--methods naive linear rbf]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import itertools

import _report
from _machine import describe

from gonio import brdf, params
from gonio.reconstruct import NaiveReconstruction, evaluate, reconstruct, testset
from gonio.rig import Rig
from studies.reconstruct.synthetic import synthesize

ROOT = Path(__file__).resolve().parent.parent
TARGET = 0.01


def material(alpha: float) -> brdf.BRDF:
    return brdf.create(
        "cook_torrance", alpha=alpha, distribution="ggx", fresnel="schlick", f0=0.04, kd=0.2
    )


def log_rmse(method: str, samples, truth, rig: Rig, pairs) -> float:  # type: ignore[no-untyped-def]
    if method == "naive":
        candidate = NaiveReconstruction(samples)
    else:
        candidate = reconstruct(samples, method=method, extrapolate="nearest")
    result = evaluate(candidate, truth, rig, isotropic=True, test_set=pairs)
    value = result.regions["all"].scores.log_rmse
    assert value is not None
    return value


def needed(counts: list[int], errors: list[float]) -> str:
    """The sample count reaching `TARGET`, log-log between the bracketing counts."""
    pairs = list(zip(counts, errors, strict=True))
    for (n0, e0), (n1, e1) in itertools.pairwise(pairs):
        if e0 > TARGET >= e1:
            t = (math.log(e0) - math.log(TARGET)) / (math.log(e0) - math.log(e1))
            return f"{math.exp(math.log(n0) + t * (math.log(n1) - math.log(n0))):,.0f}"
    if errors and errors[0] <= TARGET:
        return f"≤ {counts[0]:,}"
    return f"> {counts[-1]:,}"


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--alphas", type=float, nargs="+", default=[0.05, 0.1, 0.3])
    parser.add_argument(
        "--targets", type=int, nargs="+", default=[500, 1000, 2000, 5000, 10000, 30000]
    )
    parser.add_argument("--methods", nargs="+", default=["naive", "linear", "rbf"])
    args = parser.parse_args()
    rig = Rig.from_yaml(ROOT / "configs/rigs/arch.yaml")
    pairs = testset.draw(rig, isotropic=True)
    print(describe())
    print(f"log-RMSE on log(1 + f), {len(pairs):,} test pairs; '+' marks a method at least")
    print("as accurate as the naive reference at that count")
    for alpha in args.alphas:
        truth = material(alpha).eval
        print(f"\n### GGX α = {alpha}\n")
        head = " | ".join(f"{n:,}" for n in args.targets)
        print(f"| parametrization | method | {head} | samples for {TARGET} |")
        print("|---|---|" + "---:|" * (len(args.targets) + 1))
        for name in params.names():
            rows: dict[str, list[float]] = {}
            for n in args.targets:
                samples = synthesize(truth, rig, name, True, n, seed=3)
                for method in args.methods:
                    rows.setdefault(method, []).append(log_rmse(method, samples, truth, rig, pairs))
            for method, errors in rows.items():
                naive = rows.get("naive")
                cells = [
                    f"{e:.4f}{'' if naive is None or method == 'naive' or e > naive[i] else ' +'}"
                    for i, e in enumerate(errors)
                ]
                print(
                    f"| {name} | {method} | {' | '.join(cells)} | {needed(args.targets, errors)} |",
                    flush=True,
                )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Reconstruction accuracy against the naive grid")
