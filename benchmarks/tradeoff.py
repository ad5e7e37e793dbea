"""`gonio tradeoff`'s speed: combinations per minute of a sweep (configs/sweeps/quick.yaml
by default) on the local process pool and on a 2-worker Dask `LocalCluster` (and, with
``--modes here``, in one process), and how the wall time of one combination grows with
its sample count (planning, simulated acquisition, reconstruction and scoring).

Run: .venv/bin/python benchmarks/tradeoff.py [--sweep FILE] [--limit N] [--modes pool dask]
     [--samples 100 200 400 800 1600 3200]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tempfile
import time
from pathlib import Path

import _report
import numpy as np
from _machine import describe

from gonio.tradeoff import Sweep, load_sweep, run_sweep, runner

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "configs" / "sweeps" / "quick.yaml"


def rate(sweep: Sweep, mode: str, jobs: int) -> tuple[float, float, float]:
    """(combinations per minute, wall s of running them, s to start the cluster)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        if mode == "dask":
            from distributed import LocalCluster

            started = time.perf_counter()
            with LocalCluster(
                n_workers=jobs,
                threads_per_worker=1,
                processes=True,
                dashboard_address="127.0.0.1:0",
            ) as cluster:
                up = time.perf_counter() - started
                outcome = run_sweep(sweep, out, scheduler=cluster.scheduler_address)
        else:
            up = 0.0
            outcome = run_sweep(sweep, out, jobs=1 if mode == "here" else jobs)
    assert outcome.ran == len(sweep.tasks)
    return 60.0 * outcome.ran / outcome.wall_s, outcome.wall_s, up


def scaling(sweep: Sweep, samples: list[int]) -> None:
    """One combination (the sweep's first, its sample count replaced) per count, in this
    process, after a warm-up (imports, the test set)."""
    base = sweep.tasks[0]
    print(
        f"\none combination in one process: {base.inputs['scene']}, "
        f"{base.inputs['parametrization']} {base.inputs['sampling']}, "
        f"{base.inputs['method']}, effects {base.inputs['effects']}"
    )
    print(
        f"{'samples':>8} {'plan s':>8} {'acquire s':>10} {'evaluate s':>11} {'total s':>8} "
        f"{'ms/sample':>10}"
    )
    runner.run(base)  # warm-up
    totals = []
    for n in samples:
        plan = {**base.plan, "sampling": {**base.plan["sampling"], "target": n}}
        row = runner.run(dataclasses.replace(base, plan=plan))
        assert not row["error"], row["error"]
        totals.append(row["wall_s"])
        print(
            f"{n:>8} {row['plan_wall_s']:>8.2f} {row['acquire_wall_s']:>10.2f} "
            f"{row['evaluate_wall_s']:>11.2f} {row['wall_s']:>8.2f} "
            f"{1000 * row['wall_s'] / n:>10.2f}"
        )
    slope = np.polyfit(np.log(samples), np.log(totals), 1)[0]
    print(f"wall time ∝ samples^{slope:.2f} over {samples[0]}…{samples[-1]} samples")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", type=Path, default=QUICK)
    parser.add_argument("--limit", type=int, help="only the first N combinations")
    parser.add_argument(
        "--modes", nargs="*", default=["pool", "dask"], choices=["here", "pool", "dask"]
    )
    parser.add_argument("--jobs", type=int, default=2, help="pool processes, Dask workers")
    parser.add_argument("--samples", type=int, nargs="*", default=[100, 200, 400, 800, 1600, 3200])
    args = parser.parse_args()
    print(describe())
    sweep = load_sweep(args.sweep)
    if args.limit:
        sweep = dataclasses.replace(sweep, tasks=sweep.tasks[: args.limit])
    plan = json.dumps(sweep.spec.plan.model_dump(mode="json", exclude_defaults=True))
    print(f"sweep {sweep.path.name}: {len(sweep.tasks)} combinations; plan settings {plan}")
    print(f"{'where':28} {'comb/min':>9} {'wall':>9} {'start s':>8}")
    labels = {
        "here": "one process",
        "pool": f"local pool, {args.jobs} processes",
        "dask": f"Dask LocalCluster, {args.jobs} workers",
    }
    for mode in args.modes:
        per_minute, wall, up = rate(sweep, mode, args.jobs)
        print(f"{labels[mode]:28} {per_minute:>9.1f} {wall:>8.0f}s {up:>8.1f}")
    if args.samples:
        scaling(sweep, args.samples)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The speed of gonio tradeoff")
