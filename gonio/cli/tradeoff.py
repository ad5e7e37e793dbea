"""`gonio tradeoff SWEEP.yaml -o OUTDIR`: every combination of a sweep planned, acquired
on the simulated backend, reconstructed and scored, on a local process pool or a Dask
cluster; the results, the Pareto front of error against instrument time, figures and,
with --target-error, the fastest plan meeting it (docs/explanations/tradeoff.md)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from gonio.cli import EXIT_CODES, arguments
from gonio.cli.arguments import positive
from gonio.progress import Bar, hms

#: The exit code of a sweep whose every combination failed (the results are written).
EXIT_ALL_FAILED = 1


#: The most local worker processes per CPU of this machine: each holds a plan, a
#: simulated run and a reconstruction, so more only share the same CPUs and multiply the
#: memory.
JOBS_PER_CPU = 4


def _jobs(text: str) -> int:
    """A whole number of processes, 1 to 4 per CPU of this machine.

    The bound is `JOBS_PER_CPU` times `os.cpu_count`."""
    most = JOBS_PER_CPU * (os.cpu_count() or 1)
    return arguments.count(text, f"processes (this machine has {os.cpu_count()} CPUs)", most)


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "tradeoff",
        help=help_,
        description="Run every combination of a sweep file (scenes × parametrization, "
        "sampling, sample count, exposure, averages, motor velocity, reconstruction method, "
        "effects): plan it, acquire it on the simulated backend, reconstruct and score it "
        "against the scene. OUTDIR gets results.jsonl (one line per finished combination; a "
        "reused OUTDIR skips them), results.csv, report.md with the Pareto front of error "
        "against instrument time, and PNG figures.",
        exit_codes={
            **EXIT_CODES,
            EXIT_ALL_FAILED: "every combination failed (one line on stderr: how many, and the "
            "first reason; the results and report are written)",
        },
    )
    p.add_argument("sweep", type=Path, help="the sweep file (YAML)")
    p.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="OUTDIR",
        help="the output folder (created; a reused one resumes)",
    )
    p.add_argument(
        "--target-error",
        type=positive,
        metavar="E",
        help="also write, for each scene, the fastest plan whose error (the sweep's metric) "
        "is at most E, as OUTDIR/plans/SCENE.yaml for gonio acquire",
    )
    p.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="run on this Dask cluster (needs the distributed extra) instead of local "
        "processes; it must answer within 30 s",
    )
    p.add_argument(
        "-j",
        "--jobs",
        type=_jobs,
        help="local worker processes (default: one per CPU; 1: in this process)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_tradeoff)


def cmd_tradeoff(args: argparse.Namespace) -> int:
    from gonio.tradeoff import check_address, load_sweep

    if args.scheduler is not None:
        check_address(args.scheduler)  # before anything runs, not after the connect timeout
    sweep = load_sweep(args.sweep)
    # One per CPU by default, resolved here: the parser and its help are the same everywhere.
    jobs = args.jobs or os.cpu_count() or 1
    where = (
        f"the Dask cluster at {args.scheduler}"
        if args.scheduler
        else "this process"
        if jobs == 1
        else f"{jobs} local processes"
    )
    print(
        f"sweep {sweep.spec.name!r}: {len(sweep.tasks)} combinations over "
        f"{len(sweep.scenes)} scene(s), into {args.output} on {where}",
        flush=True,
    )
    from gonio.tradeoff import run_sweep  # the simulator, the planner: once the file is read

    outcome = run_sweep(
        sweep,
        args.output,
        jobs=jobs,
        scheduler=args.scheduler,
        target=args.target_error,
        progress=None if args.quiet else Bar(leave=False),
    )
    pace = f" ({60 * outcome.ran / outcome.wall_s:.1f} per minute)" if outcome.wall_s > 0 else ""
    print(
        f"ran {outcome.ran} combinations in {hms(outcome.wall_s)}{pace}; "
        f"{outcome.reused} were already in {args.output}"
    )
    errors = [str(r["error"]) for r in outcome.rows if r.get("error")]
    if args.target_error is not None:
        for scene in sweep.scenes:
            plan = outcome.plans.get(scene.name)
            met = f"wrote {plan}" if plan else "no combination meets it"
            print(f"target {sweep.spec.metric} ≤ {args.target_error:g} on {scene.name}: {met}")
    print(f"wrote {len(outcome.files)} files into {args.output} (report.md, results.csv, figures)")
    if errors and len(errors) == len(outcome.rows):
        print(
            f"gonio: all {len(errors)} combinations failed; the first: {errors[0]}",
            file=sys.stderr,
        )
        return EXIT_ALL_FAILED
    if errors:
        print(
            f"gonio: {len(errors)} of {len(outcome.rows)} combinations failed (their reasons "
            f"are in report.md); the first: {errors[0]}",
            file=sys.stderr,
        )
    return 0
