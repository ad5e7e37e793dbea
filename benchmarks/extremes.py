"""Round-trip accuracy at and near every named extreme, against the float64 bound.

For each parametrization, extreme (gonio.params.cases.EXTREMES) and distance (0,
1e-12, 1e-9, 1e-6 rad), the worst measured round-trip error over N sampled pairs and
the worst error that float64 coordinates impose there (half an ulp on each exact
coordinate, mapped back exactly; mpmath). Prints markdown tables for
docs/parametrizations.md. Run: .venv/bin/python benchmarks/extremes.py [--samples N]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import describe

from gonio import params
from gonio.params import cases
from gonio.params.accuracy import extreme_study


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    names = params.names()
    rows = extreme_study(names, samples=args.samples, seed=args.seed)
    print(f"machine: {describe()}")
    print(f"{args.samples} pairs per cell; cells read measured / bound (worst over the pairs)\n")
    print("| extreme | distance | " + " | ".join(names) + " |")
    print("| --- | ---: | " + " | ".join(["---:"] * len(names)) + " |")
    worst_ratio = dict.fromkeys(names, 0.0)
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
            print(f"| {extreme} | {distance:g} | " + " | ".join(cells) + " |")
    print("\nworst measured/bound ratio per parametrization (target ≤ 10):")
    for name, ratio in worst_ratio.items():
        print(f"  {name:14s} {ratio:.2f}")
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
    main()
