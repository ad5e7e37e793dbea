"""`gonio acquire PLAN.yaml -o RUN.sqlite`: measure a plan on the rig its file names
(simulated or hardware; `--rehearse`: the hardware path on emulators), journaling every
sample; `gonio acquire --resume RUN.sqlite` measures what is missing. Its exit codes
are `EXIT_CODES`.
"""

from __future__ import annotations

import argparse
import contextlib
import shlex
import sys
from pathlib import Path
from urllib.parse import quote

from drivers.errors import DriverError
from gonio import progress as planning
from gonio.acquire import RunInterrupted, control, observer
from gonio.cli import EXIT_BAD_INPUT, EXIT_INTERRUPTED, arguments
from gonio.cli.arguments import positive
from gonio.config import ConfigError

#: Exit code of a run that ended early but can be resumed.
EXIT_RESUMABLE = 3
#: What the command's exit codes mean (shown in its help and the CLI reference).
EXIT_CODES = {
    0: "the run completed (or the dry run found everything ready)",
    EXIT_BAD_INPUT: "refused before anything moved: a bad file or option, an output that "
    "exists or cannot be written, a port missing, busy or not ours to open, a motor that "
    "does not answer, is not the one the rig file expects or has settings the driver "
    "cannot work with (one line each)",
    EXIT_RESUMABLE: "the run ended early on a fault, a pause that did not clear or a full "
    "disk (resumable with --resume), or measured nothing: every target skipped "
    "(--resume --retry-skipped)",
    EXIT_INTERRUPTED: "stopped by Ctrl-C or SIGTERM (resumable with --resume)",
}


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    p = sub.add_parser(
        "acquire",
        help=help_,
        description="Measure a plan target by target on the rig its file names (simulated "
        "or Dynamixel hardware), journaling every raw sample in a SQLite run file; resume "
        "an interrupted run with --resume RUN.",
        exit_codes=EXIT_CODES,
    )
    p.add_argument("plan", type=Path, nargs="?", help="the plan file (YAML)")
    p.add_argument("-o", "--output", type=Path, help="the run file to write (SQLite)")
    p.add_argument("--rig", type=Path, help="the rig file (default: the plan's rig field)")
    p.add_argument("--scene", type=Path, help="the scene file (where the detector is simulated)")
    p.add_argument("--seed", type=arguments.seed, help="the run's seed (default: the scene's)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing run file")
    p.add_argument("--resume", type=Path, metavar="RUN", help="continue the run in RUN")
    p.add_argument(
        "--force", action="store_true", help="with --resume: accept changed plan/rig/scene files"
    )
    p.add_argument(
        "--retry-skipped", action="store_true", help="with --resume: measure skipped targets too"
    )
    p.add_argument(
        "--dry-run", action="store_true", help="check everything a run needs; move nothing"
    )
    p.add_argument(
        "--rehearse",
        action="store_true",
        help="run the hardware path against emulated devices on pseudo-terminals: the "
        "Dynamixel bus, and the rig's serial photometer or PyMeasure instrument (no "
        "hardware needed)",
    )
    p.add_argument(
        "--speedup",
        type=_speedup,
        default=50.0,
        help="--rehearse: how many times faster than real time the emulated rig runs, 1 "
        "to 1e6 (default 50)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress display")
    p.set_defaults(func=cmd_acquire)


#: The fastest a rehearsal may run: beyond, a move of the emulated motors lasts less than
#: a microsecond of real time and the rehearsal no longer exercises the drivers' waits.
MAX_SPEEDUP = 1e6


def _speedup(text: str) -> float:
    """A speed-up of the emulated rig, 1 (real time) to 1e6.

    Slower than real time would test nothing real time does not; the top is
    `MAX_SPEEDUP`."""
    value = positive(text, "a speed-up", MAX_SPEEDUP)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a speed-up of at least 1, got {text!r}")
    return value


def _resume_command(path: Path | None) -> str:
    return f"gonio acquire --resume {shlex.quote(str(path))}"


def cmd_acquire(args: argparse.Namespace) -> int:
    from gonio.cli import run_table
    from gonio.cli.render import render_summary
    from gonio.planner import load_plan_source
    from gonio.workflows import preflight, session

    progress = observer.for_stream(args.quiet)
    argv = ["gonio", *sys.argv[1:]]
    if args.resume is not None:
        if args.plan is not None or args.output is not None:
            raise ConfigError("--resume RUN continues RUN: give no plan file and no -o")
        path: Path | None = args.resume
        try:
            outcome = session.resume(
                args.resume,
                rig_path=args.rig,
                scene_path=args.scene,
                force=args.force,
                retry_skipped=args.retry_skipped,
                progress=progress,
                argv=argv,
                on_ready=lambda: _print_control(args.resume, args.quiet),
            )
        except RunInterrupted:
            return _interrupted(path)
    else:
        if args.plan is None:
            raise ConfigError("expected a plan file (or --resume RUN)")
        if args.output is None and not args.dry_run:
            raise ConfigError("-o RUN: expected the run file to write (e.g. runs/my-run.sqlite)")
        source = load_plan_source(args.plan, args.rig)
        scene = None
        scene_text = None
        if args.scene is not None:
            scene, scene_text = session.load_scene_file(args.scene, source.rig)
        files = preflight.Files(
            source.path,
            source.text,
            source.rig.source,
            source.rig.text,
            args.scene,
            scene_text,
            source.rig.alignment_text,
        )
        kind = preflight.check_scene(files, source.rig, scene, rehearse=args.rehearse)
        preflight.refuse_fly_spec(source.spec, source.rig, kind, scene, args.scene)
        if args.output is not None:
            preflight.check_output(args.output, args.overwrite, files)
        with planning.quiet() if args.quiet else contextlib.nullcontext():
            plan = source.build()
        print(render_summary(plan), flush=True)
        if args.dry_run:
            for line in preflight.dry_run(
                plan,
                files,
                scene=scene,
                output=args.output,
                overwrite=args.overwrite,
                rehearse=args.rehearse,
            ):
                # bus hygiene lines come with their level: "warning: …", "n/a: …"
                print(f"  {line}" if line.split(":")[0] in ("warning", "n/a") else f"  ok: {line}")
            print("dry run: nothing moved, nothing written")
            return 0
        path = args.output
        try:
            outcome = session.start(
                plan,
                files,
                scene=scene,
                output=args.output,
                overwrite=args.overwrite,
                seed=args.seed,
                rehearse=args.rehearse,
                speedup=args.speedup,
                progress=progress,
                argv=argv,
                on_ready=lambda: _print_control(args.output, args.quiet),
            )
        except RunInterrupted:
            return _interrupted(path)
        except DriverError:
            if not args.output.exists():  # the devices did not open: no run, no token
                control.token_path(args.output).unlink(missing_ok=True)
            raise
    print(run_table.render(outcome.run))
    report = outcome.report
    if report.outcome == "completed" and (len(outcome.run) or not len(outcome.run.plan)):
        print(f"wrote {len(outcome.run)} samples to {path}")
        return 0
    if report.outcome == "completed":  # every target skipped: nothing measured
        print(
            f"gonio: the run measured nothing: all {len(outcome.run.plan)} targets were "
            f"skipped after their faults; retry them with: {_resume_command(path)} "
            "--retry-skipped",
            file=sys.stderr,
        )
        return EXIT_RESUMABLE
    print(f"gonio: the run ended early: {report.message}", file=sys.stderr)
    print(f"resume with: {_resume_command(path)}", file=sys.stderr)
    return EXIT_RESUMABLE


def _print_control(path: Path, quiet: bool) -> None:
    """Issue the run's control token (beside it, owner-only) and print (unless
    ``quiet``) how to watch and control the run from a browser (the token in the URL's
    fragment, never sent to a server: the page sends it in a header); once every check
    has passed (the session's ``on_ready``)."""
    try:
        token = control.issue_token(path)
    except OSError as exc:
        why = exc.strerror or exc
        raise ConfigError(f"{path}: cannot write its control token: {why}") from None
    if quiet:
        return
    url = f"http://127.0.0.1:8765/run/{quote(path.name)}#token={token}"
    print(f"watch and control: gonio serve {shlex.quote(str(path))}, then open {url}", flush=True)


def _interrupted(path: Path | None) -> int:
    print("gonio: interrupted; the axes hold and every measured sample is saved", file=sys.stderr)
    print(f"resume with: {_resume_command(path)}", file=sys.stderr)
    return EXIT_INTERRUPTED
