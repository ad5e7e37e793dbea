"""`gonio plan PLAN.yaml [--rig RIG.yaml] [-o plan.csv] [--plot coverage.png] [--bounds]`."""

from __future__ import annotations

import argparse
from pathlib import Path

from gonio.config import check_output
from gonio.planner.plan import load_plan_source, render_summary


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    plan = sub.add_parser(
        "plan",
        help=help_,
        description="Place targets uniformly in the plan's parametrization, keep what the "
        "rig can reach, order them for the motors and predict the duration. Nothing moves.",
    )
    plan.add_argument("plan", type=Path, help="the plan file (YAML)")
    plan.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    plan.add_argument(
        "-o", "--output", type=Path,
        help="store the plan: a '# gonio-plan v1' header, then the ordered targets as CSV",
    )  # fmt: skip
    plan.add_argument("--plot", type=Path, help="draw the plan's coverage (needs matplotlib)")
    plan.add_argument(
        "--bounds", action="store_true",
        help="also compute the duration in generation order and the MST lower bound",
    )  # fmt: skip
    plan.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    if args.output is not None:
        check_output(args.output, "-o")
    if args.plot is not None:
        from gonio.plots import require_matplotlib

        check_output(args.plot, "--plot")
        require_matplotlib()
    plan = load_plan_source(args.plan, args.rig).build(bounds=args.bounds)
    print(render_summary(plan))
    if args.output is not None:
        plan.write(args.output)
        print(f"wrote {len(plan)} targets to {args.output}")
    if args.plot is not None:
        from gonio.plots.coverage import plot_coverage

        plot_coverage(plan, args.plot)
        print(f"drew the coverage in {args.plot}")
    return 0
