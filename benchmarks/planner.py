"""Ordering the planner's targets: how close to LKH-3 and to the lower bound, how much
faster than generation order, and how long it takes.

Four tables (moves only: settle and exposure do not depend on the order):

1. ``shipped``: every shipped plan on every shipped rig through the real planner
   (`gonio.planner.build`, ``bounds=True``, default budgets): the ordered moves
   against the Held–Karp bound and the MST (both on the relaxed any-branch time: they
   bound every order with every choice of inverse-kinematics solutions) and against
   LKH-3's tour on the very poses the planner chose (`gonio.planner.lkh`, where `elkai`
   is installed: minutes for 5 000 targets), generation order against ordered, the
   kicks tried and the wall times. Targets: ordered ≤ 1.01 × LKH, ≤ 1.02 × the bound.
2. ``trade``: time against tour length, the kick budget varied on a 5 000-target plan
   per rig (0 kicks is the descent alone).
3. ``large``: 5 000 and 50 000 Sobol targets uniform in the hybrid coordinates, both
   rigs, isotropic and anisotropic, default budgets (targets: ≤ 15 s and ≤ 60 s).
4. ``memory``: `gonio plan -o` end to end on Sobol plans of 1 000 to 1 000 000 targets
   (the cap, `placement.MAX_TARGETS`) on the arch rig, each in its own process, default
   budgets, the time cap raised to 900 s (a safety stop, not a budget: the order is
   the same on any machine unless it binds): its peak resident memory, the growth per
   target over the smallest plan (the target: ≤ 2 KB), CPU and wall time, the predicted
   moves and how the search ended; and how fast a plan over the cap is refused. The
   search's loops are compiled (numba) and loaded from the disk: a plan's first run
   after an install also compiles them (some seconds, not in these figures).

Run: .venv/bin/python benchmarks/planner.py [--tables shipped,trade,large,memory]
[--sizes 5000,50000] [--memory-sizes 1000,10000,100000,1000000] [--no-lkh]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio.planner import (
    Plan,
    PlanSpec,
    build,
    compile_kernels,
    default_kicks,
    lkh,
    load_plan,
    path_time,
)
from gonio.progress import hms
from gonio.rig import Rig

ROOT = Path(__file__).resolve().parent.parent
RIGS = {name: ROOT / f"configs/rigs/{name}.yaml" for name in ("arch", "in_plane", "arch_point")}
PLANS = {
    name: ROOT / f"configs/plans/{name}.yaml"
    for name in ("quick", "isotropic_hybrid", "anisotropic")
}
#: LKH-3 is run up to this many targets (the full matrix as text: ~1 GB at 10 000).
LKH_MAX = 6000
FLAG = {"converged": "", "move budget": " (budget)", "time cap": " (time cap)"}


def lkh_figures(plan: Plan) -> tuple[float, float] | None:
    """(LKH-3's tour on the plan's poses (s), its wall time (s)), or None."""
    if not lkh.available() or len(plan) > LKH_MAX:
        return None
    rig = plan.rig
    started = time.perf_counter()
    order = lkh.lkh_order(rig.travel, plan.angles, rig.home)
    wall = time.perf_counter() - started
    return path_time(rig.travel, rig.home, plan.angles[order]), wall


def shipped(use_lkh: bool) -> None:
    print(
        "| plan | rig | targets | ordered | Held–Karp bound | ordered / bound | LKH-3 "
        "| ordered / LKH | ordered / MST | generation / ordered | kicks (kept) "
        "| ordering (s) | bound (s) | LKH (s) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for plan_name, plan_path in PLANS.items():
        spec, _ = load_plan(plan_path)
        for rig_name, rig_path in RIGS.items():
            plan = build(spec, Rig.from_yaml(rig_path), bounds=True)
            s = plan.summary
            assert s.lower_bound_travel_s is not None and s.mst_travel_s is not None
            assert s.naive_travel_s is not None and plan.bound_wall_s is not None
            assert plan.ordering_s is not None
            ref = lkh_figures(plan) if use_lkh else None
            lk = "—" if ref is None else hms(ref[0])
            ratio = "—" if ref is None else f"{s.travel_s / ref[0]:.4f}"
            wall = "—" if ref is None else f"{ref[1]:.0f}"
            print(
                f"| {plan_name} | {rig_name} | {len(plan):,} | {hms(s.travel_s)} "
                f"| {hms(s.lower_bound_travel_s)} | {s.travel_s / s.lower_bound_travel_s:.4f} "
                f"| {lk} | {ratio} | {s.travel_s / s.mst_travel_s:.3f} "
                f"| {s.naive_travel_s / s.travel_s:.1f} "
                f"| {s.kicks:,} ({s.kicks_kept:,}){FLAG[s.stopped]} | {plan.ordering_s:.1f} "
                f"| {plan.bound_wall_s:.1f} | {wall} |",
                flush=True,
            )


def sobol_spec(n: int, isotropic: bool, kicks: int | None = None) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": "bench",
            "isotropic": isotropic,
            "sampling": {"strategy": "sobol", "target": n, "seed": 7},
            "kicks": kicks,
            "time_budget_s": 600.0,
        }
    )


def trade() -> None:
    print("| rig | plan | targets | kicks | ordered | ordered / bound | ordering (s) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    spec, _ = load_plan(PLANS["isotropic_hybrid"])
    for rig_name in ("arch", "in_plane"):
        rig = Rig.from_yaml(RIGS[rig_name])
        bound = None
        for per_target in (0.0, 0.5, 1.5, 4.0):
            n = spec.sampling.target or 0
            kicks = int(per_target * n)
            plan = build(spec.model_copy(update={"kicks": kicks}), rig, bounds=bound is None)
            s = plan.summary
            if bound is None:
                bound = s.lower_bound_travel_s
            assert bound is not None and plan.ordering_s is not None
            default = " (default)" if kicks == default_kicks(n) else ""
            print(
                f"| {rig_name} | isotropic_hybrid | {len(plan):,} | {s.kicks:,}{default} "
                f"| {hms(s.travel_s)} | {s.travel_s / bound:.4f} | {plan.ordering_s:.1f} |",
                flush=True,
            )


def large(sizes: list[int]) -> None:
    print(
        "| rig | plan | targets | generation order | ordered | Held–Karp bound "
        "| ordered / bound | ordered / MST | kicks (kept) | ordering (s) | bound (s) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for rig_name in ("arch", "in_plane"):
        rig = Rig.from_yaml(RIGS[rig_name])
        for isotropic in (False, True):
            for n in sizes:
                plan = build(sobol_spec(n, isotropic), rig, bounds=True)
                s = plan.summary
                assert s.lower_bound_travel_s is not None and s.mst_travel_s is not None
                assert s.naive_travel_s is not None and plan.bound_wall_s is not None
                assert plan.ordering_s is not None
                kind = "isotropic" if isotropic else "anisotropic"
                print(
                    f"| {rig_name} | {kind} | {len(plan):,} | {hms(s.naive_travel_s)} "
                    f"| {hms(s.travel_s)} | {hms(s.lower_bound_travel_s)}"
                    f"{'' if s.lower_bound_exact else ' (weak)'} "
                    f"| {s.travel_s / s.lower_bound_travel_s:.4f} "
                    f"| {s.travel_s / s.mst_travel_s:.3f} "
                    f"| {s.kicks:,} ({s.kicks_kept:,}){FLAG[s.stopped]} "
                    f"| {plan.ordering_s:.1f} | {plan.bound_wall_s:.1f} |",
                    flush=True,
                )


#: One `gonio plan -o` in a process of its own: prints its exit code, peak RSS (KiB) and
#: CPU seconds as JSON. Its peak memory is VmHWM, the high-water mark of this process's
#: own memory: ru_maxrss keeps, across exec, the peak of the process that forked it (this
#: benchmark, large after the `large` table), so it would report that.
_CHILD = """
import json, resource, sys
from gonio.cli import main
code = main(["plan", sys.argv[1], "-o", sys.argv[2]])
usage = resource.getrusage(resource.RUSAGE_SELF)
peak = usage.ru_maxrss
try:
    with open("/proc/self/status") as fh:
        peak = next(int(ln.split()[1]) for ln in fh if ln.startswith("VmHWM:"))
except (OSError, StopIteration):
    pass
print(json.dumps({"code": code, "rss_kib": peak, "cpu_s": usage.ru_utime +
    usage.ru_stime}), file=sys.stderr)
"""


def memory(sizes: list[int]) -> None:
    print("| targets | peak memory | growth per target | CPU | wall | moves (predicted) | search |")
    print("|---:|---:|---:|---:|---:|---:|---|")
    smallest: tuple[int, int] | None = None  # (targets, peak bytes)
    compile_kernels()  # compiled (or loaded) here: the children load them from the disk
    with tempfile.TemporaryDirectory() as folder:
        for n in [*sizes, 4_000_000]:
            path = Path(folder) / f"plan{n}.yaml"
            path.write_text(
                f"name: memory\nrig: {RIGS['arch']}\nsampling: {{strategy: sobol, target: {n}, "
                "seed: 7}\nexposure: {seconds: 0.05}\ntime_budget_s: 900\n"
            )
            stored = Path(folder) / f"plan{n}.csv"
            started = time.perf_counter()
            child = subprocess.run(
                [sys.executable, "-c", _CHILD, str(path), str(stored)],
                capture_output=True,
                text=True,
            )
            figures = json.loads(child.stderr.strip().splitlines()[-1])
            figures["wall_s"] = time.perf_counter() - started  # the process's, end to end
            if figures["code"] != 0:
                refusal = child.stderr.strip().splitlines()[0]
                print(f"| {n:,} | refused in {figures['wall_s']:.2f} s: {refusal} | | | | | |")
                continue
            rss = figures["rss_kib"] * 1024
            stored.unlink()
            smallest = smallest or (n, rss)
            per = (rss - smallest[1]) / max(n - smallest[0], 1)
            growth = "—" if n == smallest[0] else f"{per:,.0f} B"
            search = next(
                (
                    line.split(None, 1)[1]
                    for line in child.stdout.splitlines()
                    if line.strip().startswith("ordering ")
                ),
                "?",
            )
            moves = next(
                (
                    line.split("moves ", 1)[1].split(",")[0]
                    for line in child.stdout.splitlines()
                    if "predicted duration" in line
                ),
                "?",
            )
            print(
                f"| {n:,} | {rss / 2**20:,.0f} MiB | {growth} | {figures['cpu_s']:.1f} s "
                f"| {figures['wall_s']:.1f} s | {moves} | {search.strip()} |",
                flush=True,
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--tables", default="shipped,trade,large,memory")
    parser.add_argument("--memory-sizes", default="1000,10000,100000,1000000")
    parser.add_argument("--sizes", default="5000,50000")
    parser.add_argument("--no-lkh", action="store_true")
    args = parser.parse_args()
    tables = args.tables.split(",")
    print(describe())
    print(f"LKH-3 (elkai): {'installed' if lkh.available() else 'not installed'}")
    if "shipped" in tables:
        print()
        shipped(not args.no_lkh)
    if "trade" in tables:
        print()
        trade()
    if "large" in tables:
        print()
        large([int(s) for s in args.sizes.split(",")])
    if "memory" in tables:
        print()
        memory([int(s) for s in args.memory_sizes.split(",")])


def tables(argv: Sequence[str]) -> str | None:
    """A run of some of the tables has its own page: planner-<tables>.md."""
    chosen = _report.option(argv, "--tables")
    return chosen[0].replace(",", "-") if chosen else None


def title(argv: Sequence[str]) -> str:
    chosen = _report.option(argv, "--tables")
    return "Ordering the planner's targets" + (f": {chosen[0]}" if chosen else "")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title=title, variant=tables)
