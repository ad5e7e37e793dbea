"""`gonio plan PLAN.yaml [--rig RIG.yaml] [-o plan.csv] [--plot coverage.png] [--bounds]`."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path

from gonio.cli.render import render_summary
from gonio.output import reserve_output
from gonio.planner.files import load_plan_source, plan_bytes


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    plan = sub.add_parser(
        "plan",
        help=help_,
        description="Place targets uniformly in the plan's parametrization, keep what the "
        "rig can reach, order them for the motors and predict the duration. Nothing moves; "
        "nothing is written without -o (each output is created before planning and "
        "replaced whole).",
    )
    plan.add_argument("plan", type=Path, help="the plan file (YAML)")
    plan.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    plan.add_argument(
        "-o", "--output", type=Path,
        help="store the plan: a '# gonio-plan v1' header, then the ordered targets as CSV",
    )  # fmt: skip
    plan.add_argument(
        "--plot",
        type=Path,
        help="draw the plan's coverage in this figure file, its suffix naming the format "
        "(.png, .svg, .pdf, …; needs matplotlib)",
    )
    plan.add_argument(
        "--bounds", action="store_true",
        help="also compute the duration in generation order and the MST lower bound",
    )  # fmt: skip
    plan.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    if args.plot is not None:
        from gonio.plots import check_figure_format

        check_figure_format(args.plot, "--plot")
    with contextlib.ExitStack() as outputs:
        # Every output is created (as a temporary file beside it) before any work, and
        # renamed into place when whole: a refused or interrupted write leaves nothing.
        stored = None
        inputs = [args.plan, args.rig]
        if args.output is not None:
            stored = outputs.enter_context(reserve_output(args.output, "-o", inputs=inputs))
        figure = None
        if args.plot is not None:
            figure = outputs.enter_context(reserve_output(args.plot, "--plot", inputs=inputs))
        plan = load_plan_source(args.plan, args.rig).build(bounds=args.bounds)
        print(render_summary(plan))
        if stored is not None:
            stored.write_bytes(plan_bytes(plan))
            print(f"wrote {len(plan)} targets to {args.output}")
        if figure is not None:
            from gonio.plots.coverage import plot_coverage

            kind = args.plot.suffix.lower().removeprefix(".") or "png"
            figure.write_with(lambda path: plot_coverage(plan, path, format=kind))
            print(f"drew the coverage in {args.plot}")
        if stored is None:
            print(
                "nothing written: give -o PLAN.csv to store the plan "
                "(gonio.planner.read_plan reads it back)"
            )
    return 0
