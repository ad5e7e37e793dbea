"""`gonio plan PLAN.yaml [--rig RIG.yaml] [-o plan.csv] [--plot coverage.png] [--bounds]
[--budget-min M --material SPEC [--test-pairs N]]`."""

from __future__ import annotations

import argparse
import contextlib
import math
from pathlib import Path
from typing import TYPE_CHECKING

from gonio.cli.arguments import positive
from gonio.errors import GonioError
from gonio.planner import MAX_PLAN_MINUTES, load_plan_source

if TYPE_CHECKING:
    from gonio.planner import Plan, PlanSource


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    plan = sub.add_parser(
        "plan",
        help=help_,
        description="Place targets uniformly in the plan's parametrization, keep what the "
        "rig can reach, order them for the motors and predict the duration. Nothing moves; "
        "nothing is written without -o (each output is created before planning and "
        "replaced whole). With --budget-min and --material, choose the plan for a time "
        "budget: stop-and-go or fly, whichever is predicted to reconstruct the material "
        "best, never a fly plan predicted worse than the best stop-and-go one.",
    )
    plan.add_argument("plan", type=Path, help="the plan file (YAML)")
    plan.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    plan.add_argument(
        "-o",
        "--output",
        type=Path,
        help="store the plan: a '# gonio-plan v1' header, then the ordered targets as CSV",
    )
    plan.add_argument(
        "--plot",
        type=Path,
        help="draw the plan's coverage in this figure file, its suffix naming the format "
        "(.png, .svg, .pdf, …; needs matplotlib)",
    )
    plan.add_argument(
        "--bounds",
        action="store_true",
        help="also compute the duration in generation order and the MST lower bound",
    )
    plan.add_argument(
        "--budget-min",
        type=_minutes,
        metavar="M",
        help="choose the plan for M minutes of predicted instrument time: stop-and-go "
        "Sobol and warped targets in Rusinkiewicz's coordinates, fly detector arcs and θh "
        "lines, each fitted to the budget, their errors predicted for --material; prints "
        "the candidates and the choice, and -o stores the chosen plan "
        "(docs/explanations/tradeoff.md)",
    )
    plan.add_argument(
        "--material",
        metavar="SPEC",
        help="the material guess of --budget-min: a material or scene YAML file, or a model "
        "NAME:key=value,... (e.g. cook_torrance:alpha=0.05,fresnel=conductor)",
    )
    plan.add_argument(
        "--test-pairs",
        type=_pairs,
        metavar="N",
        help="test pairs the --budget-min predictions are scored on, at most "
        f"{MAX_TEST_PAIRS:,} (default 5000)",
    )
    plan.set_defaults(func=cmd_plan)


def _minutes(text: str) -> float:
    """A positive number of minutes, at most 1440 (a day).

    The bound is `gonio.planner.schema.MAX_PLAN_MINUTES`, the longest a plan is made for."""
    return positive(text, "a positive number of minutes", MAX_PLAN_MINUTES)


#: The most test pairs: every candidate plan's reconstruction is evaluated on each (about
#: a second per candidate at 10⁶), and 32 bytes a pair are held for each candidate.
MAX_TEST_PAIRS = 10**6


def _pairs(text: str) -> int:
    """A whole number of pairs, 1 to 1,000,000.

    The bound is `MAX_TEST_PAIRS`."""
    try:
        value = float(text)  # 5e3 too
    except ValueError:
        value = math.nan
    if not (1 <= value <= MAX_TEST_PAIRS and value == int(value)):
        raise argparse.ArgumentTypeError(
            f"expected a whole number of pairs in [1, {MAX_TEST_PAIRS:,}], got {text!r}"
        )
    return int(value)


def cmd_plan(args: argparse.Namespace) -> int:
    # The command's modules, imported when it runs (not for --help); the builder (scipy,
    # numba) and the backends (the refusal of a fly plan) load once the files are read.
    from gonio.cli.render import render_summary
    from gonio.output import reserve_output
    from gonio.planner import plan_bytes

    _check_choice_options(args)
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
        source = load_plan_source(args.plan, args.rig)
        if args.budget_min is None:
            from gonio.workflows import refuse_fly_detector

            refuse_fly_detector(source.spec, source.rig)  # before planning, not after it
            plan = source.build(bounds=args.bounds)
        else:
            plan = _choose(args, source)
        print(render_summary(plan))
        if stored is not None:
            stored.write_bytes(plan_bytes(plan))
            print(f"wrote {len(plan)} targets to {args.output}")
        if figure is not None:
            from gonio.plots import plot_coverage

            kind = args.plot.suffix.lower().removeprefix(".") or "png"
            figure.write_with(lambda path: plot_coverage(plan, path, format=kind))
            print(f"drew the coverage in {args.plot}")
        if stored is None:
            print(
                "nothing written: give -o PLAN.csv to store the plan "
                "(gonio.planner.read_plan reads it back)"
            )
    return 0


def _check_choice_options(args: argparse.Namespace) -> None:
    """The options of a choice come together, one line (exit 2) otherwise."""
    choosing = args.budget_min is not None
    if choosing and args.material is None:
        raise GonioError("--budget-min needs --material SPEC: the material guess it predicts for")
    if not choosing and (args.material is not None or args.test_pairs is not None):
        given = "--material" if args.material is not None else "--test-pairs"
        raise GonioError(f"{given} applies with --budget-min M (the choice of plan)")
    if choosing and args.bounds:
        raise GonioError("--bounds applies to the plan as written, not with --budget-min")


def _choose(args: argparse.Namespace, source: PlanSource) -> Plan:
    """The chosen plan for ``--budget-min`` and ``--material``, its candidates printed."""
    from gonio.cli.render import render_choice
    from gonio.tradeoff import TEST_PAIRS, choose, material_guess

    spec, rig = source.spec, source.rig
    material = material_guess(
        args.material, parametrization=spec.parametrization, isotropic=spec.isotropic, rig=rig
    )
    choice = choose(
        spec,
        rig,
        60.0 * args.budget_min,
        material,
        test_pairs=args.test_pairs or TEST_PAIRS,
        where=str(source.path),
    )
    print(render_choice(choice))
    print()
    return choice.plan
