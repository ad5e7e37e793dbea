"""`gonio fit RUN [RUN RUN] --model SPEC [--json] [-o MATERIAL.yaml] [--starts N]
[--seed S]`: fit a model family to a run's calibrated samples (docs/explanations/fitting.md)."""

from __future__ import annotations

import argparse
import contextlib
import json
from pathlib import Path
from typing import TYPE_CHECKING

from gonio.cli import arguments

if TYPE_CHECKING:
    from gonio.reconstruct import FitResult


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "fit",
        help=help_,
        description="Fit a gonio.brdf model, or a sum such as lambert+ggx, to a run's "
        "calibrated samples by weighted least squares; print the parameters with their "
        "standard errors, the reduced chi-square and the residuals by region. Three runs "
        "seen in the r, g and b bands make an RGB fit (colour parameters per channel).",
    )
    p.add_argument("runs", type=Path, nargs="+", metavar="RUN", help="the run file (or r g b)")
    p.add_argument(
        "--model",
        required=True,
        metavar="SPEC",
        help="the family, e.g. lambert+ggx (docs/explanations/fitting.md)",
    )
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    arguments.add_alignment(p)
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        metavar="MATERIAL.yaml",
        help="write the fitted model as a scene's material",
    )
    p.add_argument(
        "--starts",
        type=_starts,
        default=4,
        help=f"starting points tried, at most {MAX_STARTS} (default 4)",
    )
    p.add_argument(
        "--seed", type=arguments.seed, default=0, help="seed of the jittered starts (default 0)"
    )
    p.set_defaults(func=cmd_fit)


#: The most starting points: each is a full least-squares fit (a tenth of a second to a
#: second), so more would run for hours and find nothing the first thousand did not.
MAX_STARTS = 1000


def _starts(text: str) -> int:
    """A whole number of starting points, 1 to 1000.

    The bound is `MAX_STARTS`."""
    return arguments.count(text, "starting points", MAX_STARTS)


def cmd_fit(args: argparse.Namespace) -> int:
    from gonio.analysis import Measured, calibrate, realigned, shared_error
    from gonio.brdf import parse
    from gonio.config import ConfigError
    from gonio.errors import GonioError
    from gonio.reconstruct import fit
    from gonio.store import open_run

    if len(args.runs) not in (1, 3):
        raise ConfigError(f"expected one run, or three (r, g, b bands); got {len(args.runs)}")
    family = parse(args.model)
    with contextlib.ExitStack() as outputs:
        pending = None
        if args.output is not None:
            from gonio.output import reserve_output

            pending = outputs.enter_context(reserve_output(args.output, "-o", inputs=args.runs))
        parts, shared = [], []
        for path in args.runs:
            try:
                run = open_run(path)  # read and calibrated once for both
                if args.alignment is not None:
                    run = realigned(run, args.alignment)
                calibrated = calibrate(run) if len(run) else None  # (from_run says why)
                parts.append(Measured.from_run(run, calibrated))
                shared.append(shared_error(run, calibrated))
            except GonioError as exc:
                message = str(exc)
                raise GonioError(
                    message if str(path) in message else f"{path}: {message}"
                ) from None
        measured = parts[0] if len(parts) == 1 else Measured.rgb(*parts)
        result = fit(measured, family, starts=args.starts, seed=args.seed, shared=shared)
        if args.json:
            print(json.dumps(result.figures(), indent=2, ensure_ascii=False))
        else:
            print(render(result, measured.source))
        if pending is not None:
            pending.write_bytes(material_yaml(result, measured.source).encode())
            if not args.json:
                print(f"wrote the fitted material to {args.output}")
    return 0


def render(result: FitResult, source: str) -> str:
    """The parameter table, χ²_red and the residuals by region."""
    width = max(len(n) for n in (*result.names, "parameter"))
    lines = [
        f"fit {result.spec} to {source}: {result.samples} samples, "
        f"{len(result.names)} parameters, best of {result.starts} starts"
        + ("" if result.success else " (the optimizer did not report convergence)"),
        f"  {'parameter':<{width}}  {'value':>12}  {'std. error':>10}",
    ]
    for name, (value, err) in result.params().items():
        lines.append(f"  {name:<{width}}  {value:>12.6g}  {err:>10.2g}")
    lines.append(f"  reduced chi-square {result.chi2_red:.4g} ({result.dof} degrees of freedom)")
    lines.append(f"  {'region':<8} {'samples':>7}  {'chi2/n':>8}  {'mean r':>7}")
    for name, region in result.regions.items():
        lines.append(
            f"  {name:<8} {region.count:>7}  {region.chi2:>8.3g}  {region.mean:>+7.2f}"
            if region.count
            else f"  {name:<8} {0:>7}  {'-':>8}  {'-':>7}"
        )
    return "\n".join(lines)


def material_yaml(result: FitResult, source: str) -> str:
    """The fitted model as a scene's ``material:`` (YAML), checked as a scene checks it;
    `GonioError` (one line) when it is not a valid material."""
    import yaml

    from gonio.brdf import MaterialError, build
    from gonio.errors import GonioError

    material = result.material()
    try:
        build(material["name"], {k: v for k, v in material.items() if k != "name"})
    except MaterialError as exc:
        raise GonioError(
            f"the fitted model is not a valid material ({exc.param}: {exc}); nothing written"
        ) from None
    header = (
        f"# gonio fit --model {result.spec}: reduced chi-square {result.chi2_red:.4g} over "
        f"{result.samples} samples of {source}\n"
    )
    return header + yaml.safe_dump(material, sort_keys=False)
