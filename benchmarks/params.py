"""Throughput of forward and inverse for each parametrization on 10^6 random pairs.

Targets (2-core machine, numpy only): hybrid forward ≥ 10 M pairs/s, hybrid
inverse ≥ 5 M pairs/s, the others within 2× of hybrid. Prints a markdown table.
Run: .venv/bin/python benchmarks/params.py [--pairs N] [--repeat R]
"""

from __future__ import annotations

import argparse
import sys
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio import params
from gonio.params import cases


def rate(fn, n: int, repeat: int) -> float:
    """Pairs per second, best of ``repeat`` single runs."""
    return n / min(timeit.repeat(fn, number=1, repeat=repeat))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    wi, wo = cases.uniform(args.pairs)
    rows = {}
    for name in params.names():
        p = params.get(name)
        c = p.forward(wi, wo)
        rows[name] = (
            rate(lambda p=p: p.forward(wi, wo), args.pairs, args.repeat),
            rate(lambda p=p, c=c: p.inverse(c), args.pairs, args.repeat),
        )
    fh, ih = rows["hybrid"]
    print(f"machine: {describe()}")
    print(f"{args.pairs:,} random pairs in the upper hemisphere, best of {args.repeat}\n")
    print("| parametrization | forward (M pairs/s) | inverse (M pairs/s) | vs hybrid (fwd, inv) |")
    print("| --- | ---: | ---: | ---: |")
    for name, (f, i) in rows.items():
        print(f"| {name} | {f / 1e6:.1f} | {i / 1e6:.1f} | {f / fh:.2f}, {i / ih:.2f} |")
    print(f"\ntargets: hybrid forward ≥ 10 (got {fh / 1e6:.1f}), inverse ≥ 5 (got {ih / 1e6:.1f})")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Parametrization throughput")
