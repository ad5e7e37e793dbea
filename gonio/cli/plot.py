"""`gonio plot RUN --kind slices|polar|coverage|error -o FILE.png`: a figure of a run, its
reconstruction and a truth (docs/reference/plots.md). The figure is reserved before any work and
replaced whole (`gonio.output`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from gonio.cli.arguments import add_alignment, finite_degrees
from gonio.config import ConfigError
from gonio.output import reserve_output
from gonio.plots import DEFAULT_ANGLES_DEG, DEFAULT_THETA_I_DEG
from gonio.reconstruct import DEFAULT_METHOD, NAIVE, names

if TYPE_CHECKING:
    from gonio.analysis import Measured
    from gonio.reconstruct import Candidate, Truth

#: The figures, in the order of --help.
KINDS = ("slices", "polar", "coverage", "error")


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "plot",
        help=help_,
        description="Draw one figure of a run (needs matplotlib): slices of its "
        "reconstruction in the hybrid, orthographic and halfway/difference coordinates "
        "(--kind slices), the in-plane BRDF with the samples and the truth (polar), the "
        "samples on the hemisphere and in the plan's coordinates (coverage), or the "
        "reconstruction's error against a truth over the domain and by region (error).",
    )
    p.add_argument("run", type=Path, help="the run file (SQLite, from gonio acquire)")
    p.add_argument("--kind", required=True, choices=KINDS, help="the figure to draw")
    add_alignment(p)
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="FILE",
        help="the figure file; its suffix names the format (.png, .svg, .pdf, …)",
    )
    p.add_argument(
        "--method",
        default=DEFAULT_METHOD,
        help=f"the reconstruction: {', '.join(names())} ({NAIVE}: the reference grid; "
        f"default {DEFAULT_METHOD}); not used by coverage",
    )
    p.add_argument(
        "--parametrization",
        metavar="P",
        help="the parametrization to reconstruct in (default: the run's plan's); coverage "
        "and error draw in it too",
    )
    p.add_argument(
        "--truth",
        metavar="SPEC",
        help="what to compare with: scene (a simulated run's scene, the default where there "
        "is one), a model NAME:key=value,... (e.g. a fitted model), a material or scene "
        "YAML file, or another run file",
    )
    p.add_argument(
        "--phi-k",
        type=finite_degrees,
        nargs="+",
        metavar="DEG",
        help="slices: the values of φk − φh (hybrid, orthographic) and φd (halfway/"
        f"difference) in degrees, in [0, 180) (default {_degrees(DEFAULT_ANGLES_DEG)})",
    )
    p.add_argument(
        "--theta-i",
        type=finite_degrees,
        nargs="+",
        metavar="DEG",
        help=f"polar: the angles of incidence in degrees (default {_degrees(DEFAULT_THETA_I_DEG)})",
    )
    p.add_argument(
        "--colour",
        choices=("value", "residual"),
        default="value",
        help="coverage: colour the samples by log10 f or by (f − truth) / σ (default value)",
    )
    p.set_defaults(func=cmd_plot)


def _degrees(angles: tuple[float, ...]) -> str:
    return " ".join(f"{a:g}" for a in angles)


def cmd_plot(args: argparse.Namespace) -> int:
    from gonio.plots import check_figure_format

    check_figure_format(args.output, "-o")
    for flag, given, kind in (
        ("--phi-k", args.phi_k, "slices"),
        ("--theta-i", args.theta_i, "polar"),
    ):
        if given is not None and args.kind != kind:
            raise ConfigError(f"{flag} applies to --kind {kind}, not to --kind {args.kind}")
    if args.phi_k is not None:
        from gonio.plots import check_angles

        check_angles(args.phi_k)
    if args.parametrization is not None:
        from gonio import params

        params.get(args.parametrization)  # an unknown name fails before any work
    with reserve_output(args.output, "-o", inputs=[args.run]) as figure:
        from gonio.analysis import Measured

        measured = Measured.from_run(str(args.run), alignment=args.alignment)
        draw = _FIGURES[args.kind](args, measured)
        kind = args.output.suffix.lower().removeprefix(".") or "png"
        figure.write_with(lambda path: draw(path, kind))
    print(f"drew the {args.kind} of {args.run} in {args.output}")
    return 0


Drawing = Callable[[Path, str], None]


def _slices(args: argparse.Namespace, measured: Measured) -> Drawing:
    from gonio.plots import slices

    surface = _surface(args, measured)
    data = slices.slices(
        surface,
        args.phi_k if args.phi_k is not None else slices.DEFAULT_ANGLES_DEG,
        title=f"{_label(args, measured)} of {args.run} ({len(measured)} samples)",
    )
    return lambda path, kind: slices.draw(data, path, format=kind)


def _polar(args: argparse.Namespace, measured: Measured) -> Drawing:
    from gonio.plots import polar

    theta_i = args.theta_i if args.theta_i is not None else polar.DEFAULT_THETA_I_DEG
    polar.check_theta_i(theta_i, measured.rig.theta_max)
    truth = None
    if args.truth is not None or measured.scene_text is not None:
        truth = _truth(args, measured)
    data = polar.polar(
        _surface(args, measured),
        (measured.wi, measured.wo, measured.f, measured.sigma),
        measured.rig.theta_max,
        theta_i,
        truth=None if truth is None else truth.eval,
        surface_label=_label(args, measured),
        truth_label=None if truth is None else truth.label,
        title=f"in-plane BRDF of {args.run} ({len(measured)} samples)",
    )
    return lambda path, kind: polar.draw(data, path, format=kind)


def _coverage(args: argparse.Namespace, measured: Measured) -> Drawing:
    from gonio.plots import samples

    truth = _truth(args, measured) if args.colour == "residual" else None
    data = samples.coverage(
        (measured.wi, measured.wo, measured.f, measured.sigma),
        args.parametrization or measured.parametrization,
        isotropic=measured.isotropic,
        theta_max=measured.rig.theta_max,
        colour_by=args.colour,
        truth=None if truth is None else truth.eval,
        title=f"the {len(measured)} samples of {args.run}"
        + ("" if truth is None else f" against {truth.label}"),
    )
    return lambda path, kind: samples.draw(data, path, format=kind)


def _error(args: argparse.Namespace, measured: Measured) -> Drawing:
    from gonio.plots import error
    from gonio.reconstruct import DEFAULT_FILL, reconstruction, testset

    truth = _truth(args, measured)
    # Every test pair, as `gonio evaluate` scores them: the fill outside the support.
    surface = reconstruction(measured, args.method, args.parametrization, extrapolate=DEFAULT_FILL)
    pairs = testset.draw(measured.rig, isotropic=measured.isotropic)
    truth_supported = None
    if truth.supported is not None:
        truth_supported = truth.supported(pairs.wi, pairs.wo)
    data = error.errors(
        surface,
        truth.eval,
        pairs,
        args.parametrization or measured.parametrization,
        truth_supported=truth_supported,
        title=f"{_label(args, measured)} of {args.run} against {truth.label} "
        f"({len(pairs)} test pairs, seed {pairs.seed})",
    )
    return lambda path, kind: error.draw(data, path, format=kind)


_FIGURES: dict[str, Callable[[argparse.Namespace, Measured], Drawing]] = {
    "slices": _slices,
    "polar": _polar,
    "coverage": _coverage,
    "error": _error,
}


def _surface(args: argparse.Namespace, measured: Measured) -> Candidate:
    from gonio.reconstruct import reconstruction

    return reconstruction(measured, args.method, args.parametrization)


def _truth(args: argparse.Namespace, measured: Measured) -> Truth:
    from gonio.reconstruct import reconstruction, truth_from_spec

    return truth_from_spec(
        args.truth,
        measured,
        reconstruct=lambda other: reconstruction(other, args.method, args.parametrization),
    )


def _label(args: argparse.Namespace, measured: Measured) -> str:
    return f"{args.method} reconstruction ({args.parametrization or measured.parametrization})"
