"""`gonio evaluate RUN`: a reconstruction of a run scored against a truth (the simulated
scene by default) on the fixed test set, overall and by region (docs/explanations/evaluation.md)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from gonio.cli.arguments import add_alignment
from gonio.reconstruct import DEFAULT_FILL, DEFAULT_METHOD, FILLS, NAIVE, names
from gonio.reconstruct import reconstruction as _reconstruction


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "evaluate",
        help=help_,
        description="Reconstruct a run's BRDF and score it against a truth on a fixed, "
        "seeded set of pairs the rig can measure: log-RMSE, cosine-weighted log-RMSE, "
        "relative RMSE, median and 95th-percentile relative error, overall and near the "
        "mirror direction, near retro-reflection, at grazing angles and elsewhere. Every "
        "test pair is scored (outside the reconstruction's support with its fill) unless "
        "--only-supported; the coverage column is the share inside the support.",
    )
    p.add_argument("run", type=Path, help="the run file (SQLite, from gonio acquire)")
    p.add_argument(
        "--truth",
        metavar="SPEC",
        help="what to compare with: scene (a simulated run's scene, the default), a model "
        "NAME:key=value,... (e.g. cook_torrance:alpha=0.1), a material or scene YAML file, "
        "or another run file (reconstructed the same way)",
    )
    p.add_argument(
        "--method",
        default=DEFAULT_METHOD,
        help=f"the reconstruction: {', '.join(names())} ({NAIVE}: the reference grid; "
        f"default {DEFAULT_METHOD})",
    )
    p.add_argument(
        "--parametrization",
        metavar="P",
        help="the parametrization to reconstruct in (default: the run's plan's)",
    )
    p.add_argument(
        "--extrapolate",
        choices=FILLS,
        default=DEFAULT_FILL,
        help="the fill outside the support: nearest (the inverse-distance mean of the "
        "nearest samples, in log(1 + f)) or model (model+residual's fitted model); "
        f"default {DEFAULT_FILL}",
    )
    p.add_argument(
        "--only-supported",
        action="store_true",
        help="score only the test pairs inside the reconstruction's support (no fill)",
    )
    p.add_argument("--json", action="store_true", help="print the scores as JSON")
    add_alignment(p)
    p.set_defaults(func=cmd_evaluate)


def cmd_evaluate(args: argparse.Namespace) -> int:
    from gonio.analysis import Measured
    from gonio.reconstruct import evaluate, truth_from_spec

    if args.parametrization is not None:
        from gonio import params

        params.get(args.parametrization)  # an unknown name fails before any work
    measured = Measured.from_run(str(args.run), alignment=args.alignment)
    truth = truth_from_spec(
        args.truth,
        measured,
        reconstruct=lambda other: _reconstruction(other, args.method, args.parametrization),
    )
    fill = None if args.only_supported else args.extrapolate
    candidate = _reconstruction(measured, args.method, args.parametrization, extrapolate=fill)
    parametrization = args.parametrization or measured.parametrization
    label = f"{args.method} ({parametrization}, {len(measured)} samples of {args.run})"
    result = evaluate(
        candidate,
        truth,
        measured.rig,
        isotropic=measured.isotropic,
        candidate_label=label,
        only_supported=args.only_supported,
    )
    if args.json:
        print(json.dumps(result.to_json(), indent=2, ensure_ascii=False))
    else:
        print(result.table())
    return 0
