"""Round-trip accuracy at and near every named extreme, against the float64 bound.

For each parametrization, extreme (gonio.params.cases.EXTREMES) and distance (0,
1e-12, 1e-9, 1e-6 rad), the worst measured round-trip error over N sampled pairs and
the worst error that float64 coordinates impose there (half an ulp on each exact
coordinate, mapped back exactly; mpmath). Prints markdown tables for
docs/explanations/parametrizations.md. Run: .venv/bin/python studies/extremes.py [--samples N]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # studies
import _report
from _machine import describe

from gonio import params
from gonio.params import cases
from studies.params import exact
from studies.params.accuracy import extreme_study, measured_errors


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--near-horizon", type=int, default=3000, help="random pairs per name")
    args = ap.parse_args()
    names = params.names()
    rows = extreme_study(names, samples=args.samples, seed=args.seed)
    print(f"machine: {describe()}")
    print(f"{args.samples} pairs per cell; cells read measured / bound (worst over the pairs)\n")
    print("| extreme | distance | " + " | ".join(names) + " |")
    print("| --- | ---: | " + " | ".join(["---:"] * len(names)) + " |")
    worst_ratio = dict.fromkeys(names, 0.0)
    worst_pair = dict.fromkeys(names, 0.0)
    for extreme in cases.EXTREMES:
        for distance in cases.DISTANCES:
            cells = []
            for name in names:
                (r,) = [
                    r
                    for r in rows
                    if r.extreme == extreme and r.distance == distance and r.parametrization == name
                ]
                cells.append(f"{r.measured:.1e} / {r.bound:.1e}")
                worst_ratio[name] = max(worst_ratio[name], r.ratio)
                worst_pair[name] = max(worst_pair[name], r.pair_ratio)
            print(f"| {extreme} | {distance:g} | " + " | ".join(cells) + " |")
    print("\nworst measured / bound per parametrization (target ≤ 10):")
    print("  parametrization  cell worst / cell worst  pair by pair")
    for name in names:
        print(f"  {name:15s}  {worst_ratio[name]:23.2f}  {worst_pair[name]:12.2f}")
    print(f"\n{args.near_horizon} random pairs crossing the √ε regime (cases.near_horizon):")
    print("  parametrization  worst measured / bound, pair by pair")
    wi, wo = cases.near_horizon(args.near_horizon, seed=args.seed)
    for name in names:
        ratio = measured_errors(name, wi, wo) / exact.roundtrip_bounds(name, wi, wo)
        print(f"  {name:15s}  {np.max(ratio):.2f}")
    print("\nworst measured error per extreme (any distance):")
    print("| extreme | " + " | ".join(names) + " |")
    print("| --- | " + " | ".join(["---:"] * len(names)) + " |")
    for extreme in cases.EXTREMES:
        worst = [
            max(r.measured for r in rows if r.extreme == extreme and r.parametrization == name)
            for name in names
        ]
        print(f"| {extreme} | " + " | ".join(f"{w:.1e}" for w in worst) + " |")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Round-trip accuracy at the extremes")
