"""Ordering the planner's targets: how close to the lower bound, how much faster than
generation order, and how long it takes.

For both shipped rigs, anisotropic plans (every axis moves) and isotropic plans (the
sample rotation stays home) of 5 000 and 50 000 Sobol targets uniform in the hybrid
coordinates go through the real planner (`gonio.planner.plan.build`); the table gives
the move time (travel only: settle and exposure do not depend on the order) in
generation order (with the same choice of inverse-kinematics solutions), after the
constructive order (on the solutions nearest home), of the final plan (2-opt/Or-opt,
solutions re-chosen along the order, improved again), the minimum spanning tree over
the poses measured, the ratios the issue sets targets for (ordered ≤ 1.3 × MST,
generation order ≥ 2 × ordered), the improving moves the ordering applied (the default
budget is 10 per target + 100: "(budget)" if it bound, "(time cap)" if the wall-clock
safety cap did, which makes the order machine-dependent) and the wall time of ordering
(construction, improvement and the choice of solutions; safety cap 30 s) and of the
lower bound (`build(..., bounds=True)`).
Run: .venv/bin/python benchmarks/planner.py [--sizes 5000,50000]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import describe

from gonio.planner.plan import build, hms
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig

ROOT = Path(__file__).resolve().parent.parent
RIGS = {"arch": ROOT / "configs/rigs/arch.yaml", "in_plane": ROOT / "configs/rigs/in_plane.yaml"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="5000,50000")
    parser.add_argument("--budget", type=float, default=30.0)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    print(describe())
    print()
    print(
        "| rig | plan | targets | generation order | constructed | ordered | MST bound "
        "| ordered / MST | generation / ordered | moves | ordering (s) | bound (s) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for rig_name, rig_path in RIGS.items():
        rig = Rig.from_yaml(rig_path)
        for isotropic in (False, True):
            for n in sizes:
                spec = PlanSpec.model_validate(
                    {
                        "name": "bench",
                        "isotropic": isotropic,
                        "sampling": {"strategy": "sobol", "target": n, "seed": 7},
                        "time_budget_s": args.budget,
                    }
                )
                plan = build(spec, rig, bounds=True)
                o, s = plan.ordering, plan.summary
                assert o is not None
                assert s.naive_travel_s is not None and s.lower_bound_travel_s is not None
                flag = {"converged": "", "move budget": " (budget)", "time cap": " (time cap)"}
                kind = "isotropic" if isotropic else "anisotropic"
                print(
                    f"| {rig_name} | {kind} | {len(plan)} | {hms(s.naive_travel_s)} "
                    f"| {hms(o.constructed_s)} | {hms(s.travel_s)} "
                    f"| {hms(s.lower_bound_travel_s)}"
                    f"{'' if s.lower_bound_exact else ' (weak)'} "
                    f"| {s.travel_s / s.lower_bound_travel_s:.3f} "
                    f"| {s.naive_travel_s / s.travel_s:.1f} "
                    f"| {s.moves:,}{flag[s.stopped]} "
                    f"| {s.ordering_s:.1f} "
                    f"| {s.bound_wall_s:.1f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
