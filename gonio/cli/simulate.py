"""`gonio simulate PLAN.yaml --scene SCENE.yaml`: the plan measured by the acquisition
engine on the simulated backend (`gonio.workflows.simulate.simulate_plan`: the loop, journal and
calibration of `gonio acquire`), and what it cost and how accurate it was.

The summary says how long the real rig would take, how long the simulation took, and
how far the recovered BRDF is from the scene's model at the pairs the optics saw: what a
plan and a set of effects cost in accuracy, before any hardware moves. Without ``-o``
the run journal lives in memory and nothing is written.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

import numpy as np

from gonio import progress as planning
from gonio.acquire import observer
from gonio.analysis import error_figures
from gonio.cli import arguments
from gonio.cli.run_table import render
from gonio.planner import load_plan_source
from gonio.rig import footprint_ok, view_on_sample
from gonio.workflows import Result, preflight, session, simulate_plan

#: Exit code of a simulated run that measured nothing (every target failed or the run
#: ended before the first).
EXIT_NOTHING_MEASURED = 3
#: What the command's exit codes mean (shown in its help and the CLI reference).
EXIT_CODES = {
    0: "the run measured at least one target (a run that ended early says so)",
    2: "refused before anything ran: a bad file or option (one line)",
    EXIT_NOTHING_MEASURED: "the run measured nothing: every target failed, or the run "
    "ended before the first (one line saying why)",
}


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "simulate",
        help=help_,
        exit_codes=EXIT_CODES,
        description="Plan, then measure every target with the acquisition engine on the "
        "simulated backend (virtual motors and detector, the scene's material, noise and "
        "faults), calibrate with the reference standard, and report instrument time, wall "
        "time and the error of the recovered BRDF, with a warning for saturated readings "
        "and for spots that overrun the sample. -o keeps the run file (as gonio acquire "
        "writes it).",
    )
    p.add_argument("plan", type=Path, help="the plan file (YAML)")
    p.add_argument("--scene", type=Path, required=True, help="the scene file (YAML)")
    p.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    p.add_argument("--seed", type=arguments.seed, help="the run's seed (default: the scene's)")
    p.add_argument("--no-effects", action="store_true", help="ignore the scene's effects")
    p.add_argument("-o", "--output", type=Path, help="keep the run file (SQLite) here")
    p.add_argument("--overwrite", action="store_true", help="replace an existing run file")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=cmd_simulate)


def render_result(result: Result) -> str:
    scene = result.scene
    effects = ", ".join(scene.effects.names()) or "none"
    errors = error_figures(result.run, result.truth, recovered=result.brdf)
    instrument = render(result.run, errors, title=False).splitlines()
    time_line = next(i for i, line in enumerate(instrument) if "instrument time" in line)
    instrument.insert(
        time_line + 1,
        f"  {'wall time':<24}{result.wall_s:>9.2f}s   (1/"
        f"{_instrument_s(result) / max(result.wall_s, 1e-9):,.0f} of the instrument time)",
    )
    lines = [f"scene {scene.name!r} (effects: {effects}), seed {result.run.meta['seed']}"]
    lines += instrument
    lines += _saturation_note(result) + _footprint_note(result)
    return "\n".join(lines)


def _instrument_s(result: Result) -> float:
    times = [e.t_s for e in result.run.events] + result.run.samples["ended_s"].tolist()
    return float(max(times) - min(times)) if times else 0.0


def _saturation_note(result: Result) -> list[str]:
    saturated = int(np.count_nonzero(result.saturated))
    if not saturated:
        return []
    return [
        f"  warning: {saturated} of {len(result.run)} readings "
        f"({100 * saturated / max(len(result.run), 1):.1f} %) are saturated even at the "
        "shortest exposure tried: their BRDF values are lower bounds"
    ]


def _footprint_note(result: Result) -> list[str]:
    """Targets whose spot overruns the sample at the angles reached (the true ones: the
    planner refused overruns at the commanded angles, a position error can still cross
    the edge): a collimated beam's lit ellipse off the sample or out of the detector's
    view, or, with the footprint effect (which models the holder the view then takes
    in), a point-source detector's view past the sample's edge."""
    rig, n = result.plan.rig, len(result.true_wi)
    c = rig.spec.constraints
    if not n:
        return []
    if c.beam_diameter_mm is not None:
        over = ~footprint_ok(
            result.true_wi,
            result.true_wo,
            c.beam_diameter_mm,
            c.sample_diameter_mm,
            c.detector_fov_mm,
        )
        what = "the beam's footprint leaves the sample or the detector's view"
    elif rig.source_kind == "point" and result.scene.effects.footprint is not None:
        over = ~view_on_sample(result.true_wo, c.detector_fov_mm, c.sample_diameter_mm)
        what = "the detector's field of view reaches past the sample's edge"
    else:
        return []
    count = int(np.count_nonzero(over))
    if not count:
        return []
    return [
        f"  warning: at {count} of {n} targets ({100 * count / n:.1f} %) {what} at the "
        "angles reached: their readings miss light that the BRDF assumes"
    ]


def cmd_simulate(args: argparse.Namespace) -> int:
    if args.output is not None:
        preflight.check_output(args.output, args.overwrite)
    source = load_plan_source(args.plan, args.rig)
    scene, text = session.load_scene_file(args.scene, source.rig)
    preflight.refuse_fly_spec(source.spec, source.rig, "simulated", scene, args.scene)
    if args.no_effects:
        scene = scene.with_effects([])
        from gonio.config import spec_text

        text = spec_text(scene)
    files = preflight.Files(
        source.path,
        source.text,
        source.rig.source,
        source.rig.text,
        args.scene,
        text,
        source.rig.alignment_text,
    )
    with planning.quiet() if args.quiet else contextlib.nullcontext():
        plan = source.build()
    result = simulate_plan(
        plan,
        scene,
        args.seed,
        files=files,
        output=args.output,
        overwrite=args.overwrite,
        progress=observer.for_stream(args.quiet),
    )
    print(
        f"simulated plan {plan.spec.name!r} on rig {plan.rig.spec.name!r}, {render_result(result)}"
    )
    if args.output is not None:
        print(f"wrote {len(result.run)} samples to {args.output}")
    else:
        print("nothing written: give -o RUN.sqlite to keep the run file (read it with gonio info)")
    if not len(result.run):
        report = result.report
        print(
            f"gonio: the run measured nothing (outcome {report.outcome}, 0 of "
            f"{len(plan)} targets): {report.message or 'every target was skipped'}",
            file=sys.stderr,
        )
        return EXIT_NOTHING_MEASURED
    return 0
