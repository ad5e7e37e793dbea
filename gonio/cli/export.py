"""`gonio export RUN.sqlite -o PATH [--format F]`: a run in another program's format
(csv, hdf5, alta, bluesky; merl, rgl and factored from the run's reconstruction).
docs/reference/formats.md."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from gonio.cli import arguments
from gonio.reconstruct import DEFAULT_METHOD, names

#: The most grid points per coordinate the option takes; the memory the grid needs
#: bounds it further (`gonio.export.check_options`).
MAX_GRID_POINTS = 10_000


def _grid_points(text: str) -> int:
    """A whole number of points, 1 to 10 000, within the memory.

    The bound is `MAX_GRID_POINTS`; the grid's memory is checked before any work."""
    return arguments.count(text, "grid points", MAX_GRID_POINTS)


def _terms(most: int, what: str) -> Callable[[str], int]:
    """The type of a count of a factorization's terms, 1 to ``most``."""

    def terms(text: str) -> int:
        return arguments.count(text, what, most)

    terms.__doc__ = f"A whole number of {what}, 1 to {most}."
    return terms


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    from gonio.export import (
        ALTA_PARAMS,
        FORMATS,
        MAX_INNER,
        MAX_OUTER,
        MERL_FILLS,
        MIN_SUPPORTED,
        RGL_COLORS,
        SUFFIXES,
    )

    p = sub.add_parser(
        "export",
        help=help_,
        description="Write a run in another program's format: "
        + "; ".join(f"{name}: {what}" for name, (_, what) in FORMATS.items())
        + ". The output is written whole or not at all (an existing file is replaced). "
        "Layouts, units and what each format loses: docs/reference/formats.md.",
    )
    p.add_argument("run", type=Path, help="the run file (SQLite, from gonio acquire)")
    p.add_argument(
        "--format",
        metavar="FORMAT",
        help=f"the output format, any case: {', '.join(FORMATS)} (default: the one -o's "
        "suffix says: " + ", ".join(f"{k} {v}" for k, v in SUFFIXES.items()) + ")",
    )
    arguments.add_alignment(p)
    p.add_argument("-o", "--output", required=True, type=Path, help="the file to write")
    p.add_argument(
        "--alta-param",
        choices=ALTA_PARAMS,
        default="stark_3d",
        help="alta: the input parametrization (default stark_3d, ALTA's STARK_3D)",
    )
    p.add_argument(
        "--merl-fill",
        choices=MERL_FILLS,
        default="missing",
        help="merl: bins outside the measured support are written missing (negative, "
        "the default) or filled by the reconstruction's extrapolation",
    )
    p.add_argument(
        "--rgl-color",
        choices=RGL_COLORS,
        default="spectral",
        help="rgl: write a spectrum (the default; grey and one-band runs flat over their "
        "band, RGB upsampled) or RGB",
    )
    p.add_argument(
        "--grid",
        metavar="PARAMETRIZATION",
        help="hdf5: also write the reconstruction on a regular grid of this "
        "parametrization's isotropic coordinates",
    )
    p.add_argument(
        "--grid-points",
        type=_grid_points,
        default=32,
        help="hdf5: grid points per coordinate, as many as the memory holds (default 32)",
    )
    p.add_argument(
        "--method",
        default=DEFAULT_METHOD,
        help="merl, rgl, factored, hdf5 --grid: the reconstruction tabulated "
        f"({', '.join(names())}; default {DEFAULT_METHOD})",
    )
    p.add_argument(
        "--outer",
        type=_terms(MAX_OUTER, "outer terms"),
        default=2,
        help="factored: outer terms J (default 2)",
    )
    p.add_argument(
        "--inner",
        type=_terms(MAX_INNER, "inner terms"),
        default=2,
        help="factored: inner terms K per outer term (default 2)",
    )
    p.add_argument(
        "--allow-sparse",
        action="store_true",
        help="merl, rgl, factored, hdf5 --grid: write the grid even from fewer samples than "
        f"one simplex, or when they support less than {MIN_SUPPORTED * 100:.0f}%% of it (a "
        "warning on stderr gives the share); without it such an export is refused",
    )
    p.add_argument(
        "-q", "--quiet", action="store_true", help="no progress display; print nothing on success"
    )
    p.set_defaults(func=cmd_export)


def cmd_export(args: argparse.Namespace) -> int:
    from gonio import params, progress
    from gonio.export import Options, check_options, export, format_of
    from gonio.reconstruct import methods

    args.format = format_of(args.output, args.format)

    if args.grid is not None:
        params.get(args.grid)  # an unknown name: one line, before any work
    methods.check(args.method)
    options = Options(
        alta_param=args.alta_param,
        merl_fill=args.merl_fill,
        grid=args.grid,
        grid_points=args.grid_points,
        outer=args.outer,
        inner=args.inner,
        rgl_color=args.rgl_color,
        method=args.method,
        allow_sparse=args.allow_sparse,
        alignment=args.alignment,
    )
    check_options(args.format, options)  # before any work: one line
    # Each long step is named on a terminal as it starts (no delay: a step that runs in
    # compiled code cannot advance a bar to make it appear later).
    shown = progress.quiet() if args.quiet else progress.shown_on(sys.stderr, delay_s=0.0)
    with shown:
        summary = export(args.run, args.format, args.output, options)
    for line in summary.splitlines():
        if line.startswith("warning: "):
            print(f"gonio: {line}", file=sys.stderr)
        elif not args.quiet:
            print(line)
    return 0
