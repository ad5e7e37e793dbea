"""The ``gonio`` command line: one parser, one subcommand per job (presentation only:
parsing, printing, exit codes; the work is done by the domain packages).

Subcommand modules are imported only when their command runs, so ``gonio --help`` does
not pay for scipy or the simulator. Errors a user can cause (``GonioError``, and
``DriverError`` from the hardware layer) become one line on stderr and exit code 2;
anything else is a bug and keeps its traceback. Ctrl-C exits with code 130 and one line.
A usage error is one line too, with where to read the usage (`UsageParser`). A reader
that closes the pipe early (``gonio plan … | head -1``) ends the command quietly with
exit code 141, as Unix tools killed by SIGPIPE do. `EXIT_CODES` lists them; a command
whose codes mean more declares its own (``exit_codes=`` of its parser, shown in its help).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
from collections.abc import Mapping, Sequence
from typing import Any, NoReturn, TextIO, cast

from drivers.errors import DriverError
from gonio import __version__
from gonio.errors import GonioError

#: name → (module with ``add_parser(sub, help_)``, the command's one-line help: the only
#: copy, shown by ``gonio --help`` and passed to the module when it builds its parser).
COMMANDS: dict[str, tuple[str, str]] = {
    "tables": (
        "gonio.cli.tables",
        "the parametrizations on named direction pairs and the lobe comparison, as tables",
    ),
    "plan": (
        "gonio.cli.plan",
        "turn a plan file into ordered motor targets, with counts and durations",
    ),
    "simulate": (
        "gonio.cli.simulate",
        "measure a plan on the simulated rig and compare with the scene's truth",
    ),
    "acquire": (
        "gonio.cli.acquire",
        "measure a plan on the rig (simulated or hardware), journaling every sample",
    ),
    "evaluate": (
        "gonio.cli.evaluate",
        "score a run's reconstruction against a truth (the scene, a model, another run)",
    ),
    "plot": (
        "gonio.cli.plot",
        "draw a run: reconstruction slices, in-plane curves, sample coverage, error by region",
    ),
    "tradeoff": (
        "gonio.cli.tradeoff",
        "sweep plans over scenes and axes: error against instrument time, the fastest plan",
    ),
    "align": (
        "gonio.cli.align",
        "measure the rig's misalignment with a mirror and write its alignment file; --check it",
    ),
    "info": ("gonio.cli.info", "what a run file holds: progress, time, faults, calibration"),
    "serve": (
        "gonio.cli.serve",
        "a local web page of runs, live as samples land; pause, resume, stop with the run's token",
    ),
    "watch": ("gonio.cli.watch", "a run live in the terminal: progress, ETA, samples, events"),
    "export": (
        "gonio.cli.export",
        "write a run as csv, hdf5, alta, bluesky documents, a MERL table or an RGL material",
    ),
    "fit": (
        "gonio.cli.fit",
        "fit a BRDF model (or a sum, lambert+ggx) to a run's samples, with uncertainties",
    ),
    "motors": (
        "gonio.cli.motors",
        "a Dynamixel bus: scan, status, reboot; bring-up: move, home, torque, set-id",
    ),
    "detector": (
        "gonio.cli.detector",
        "a serial detector: check-stream qualifies its streaming for fly plans on hardware",
    ),
    "schema": (
        "gonio.cli.schema",
        "the JSON Schema of a plan, rig, scene or sweep file, for an editor to check it",
    ),
}


#: Exit code of bad input: a usage error, or a file, field, option or device refused.
EXIT_BAD_INPUT = 2
#: Exit code of a command stopped by Ctrl-C (128 + SIGINT, as Unix tools).
EXIT_INTERRUPTED = 130
#: Exit code of a command whose reader closed the pipe (128 + SIGPIPE, as Unix tools).
EXIT_BROKEN_PIPE = 141
#: Exit code of a command whose standard output is closed or cannot be written (a full
#: disk, /dev/full): sysexits' EX_IOERR.
EXIT_NO_OUTPUT = 74

#: Every command's exit codes (a command's own meanings are in its parser's `exit_codes`).
EXIT_CODES: dict[int, str] = {
    0: "done (or the help printed)",
    1: "an unexpected error, that is a bug: Python's traceback is printed "
    "(a few commands also use 1, for an answer they list)",
    EXIT_BAD_INPUT: "bad input: a usage error, or a file, field, option or device refused, "
    "in one line on stderr",
    EXIT_INTERRUPTED: "interrupted by Ctrl-C, in one line on stderr",
    EXIT_BROKEN_PIPE: "the reader closed the pipe early (head -1 reading the output, say): "
    "the command stops quietly",
    EXIT_NO_OUTPUT: "the standard output is closed or cannot be written (a full disk, "
    "/dev/full), in one line on stderr",
}


class UsageParser(argparse.ArgumentParser):
    """An `argparse.ArgumentParser` whose usage errors are one line with exit code 2:
    ``gonio: error: plan: the following arguments are required: plan (see gonio plan
    --help)``, instead of argparse's usage block wrapped over several lines. Subcommand
    parsers are made of the same class (argparse builds them with the parent's type).

    ``exit_codes`` (code → meaning): what the command's exit codes mean, where it says
    more than `EXIT_CODES`; kept as `exit_codes` and shown as the help's epilog.
    """

    def __init__(
        self, *args: Any, exit_codes: Mapping[int, str] | None = None, **kwargs: Any
    ) -> None:
        self.exit_codes = dict(exit_codes or {})
        if self.exit_codes:
            text = "exit codes: " + "; ".join(f"{c} {w}" for c, w in self.exit_codes.items())
            kwargs["epilog"] = "\n\n".join(filter(None, [kwargs.get("epilog"), text]))
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, usage_error(self.prog, message) + "\n")


def usage_error(prog: str, message: str) -> str:
    """The one line of a usage error of the command ``prog`` (e.g. ``gonio plan``)."""
    where = prog.removeprefix("gonio").strip()
    return f"gonio: error: {where + ': ' if where else ''}{message} (see {prog} --help)"


def _command_of(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line (the first word not an option)."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(
    command: str | None = None, *, parser_class: type[UsageParser] = UsageParser
) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (all of them if ``"*"``).
    ``parser_class``: the class of it and of every subcommand's parser (a subclass of
    `UsageParser`, e.g. one that records the arguments for the reference page)."""
    parser = parser_class(
        prog="gonio",
        description="A virtual gonioreflectometer with a hardware driver layer.",
        exit_codes=EXIT_CODES,
    )
    parser.add_argument("--version", action="version", version=f"gonio {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in COMMANDS.items():
        if command in (name, "*"):
            importlib.import_module(module).add_parser(sub, help_)
        else:
            sub.add_parser(name, help=help_, add_help=False)
    return parser


def _prog(args: argparse.Namespace) -> str:
    """``gonio`` and the (sub)command words of ``args`` (for a usage error's hint)."""
    words = [getattr(args, key, None) for key in ("command", "motors_command", "detector_command")]
    return " ".join(["gonio", *(w for w in words if w)])


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if sys.stdout is None:  # started with its standard output closed (``>&-``)
        print("gonio: error: the standard output is closed", file=sys.stderr)
        return EXIT_NO_OUTPUT
    given = sys.stdout
    watched = _WatchedOutput(given)
    sys.stdout = proxy = cast(TextIO, watched)
    try:
        try:
            code = _run(argv)
        finally:  # argparse's help exits: its text is flushed here too
            sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
    except BrokenPipeError:
        return _broken_pipe()
    except OSError as exc:
        if exc is not watched.failed:  # another file's error
            raise
        return _no_output(exc)
    except SystemExit:
        if watched.failed is None:
            raise
        return _no_output(watched.failed)
    finally:
        if sys.stdout is proxy:
            sys.stdout = given
    if watched.failed is not None:  # an error a library kept to itself (argparse's help)
        return _no_output(watched.failed)
    return code


def _no_output(exc: OSError) -> int:
    """The standard output could not be written: one line (nothing for a closed pipe)."""
    if isinstance(exc, BrokenPipeError):
        return _broken_pipe()
    print(f"gonio: error: cannot write the standard output: {exc.strerror or exc}", file=sys.stderr)
    _stdout_to_devnull()
    return EXIT_NO_OUTPUT


class _WatchedOutput:
    """The standard output as given, keeping the error a write or flush to it raised
    (so that error, and no other file's, is told as the output's)."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.failed: OSError | None = None

    def write(self, text: str) -> int:
        try:
            return self.stream.write(text)
        except OSError as exc:
            self.failed = exc
            raise

    def flush(self) -> None:
        try:
            self.stream.flush()
        except OSError as exc:
            self.failed = exc
            raise

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


def _run(argv: list[str]) -> int:
    parser = build_parser(_command_of(argv))
    args, extra = parser.parse_known_args(argv)
    if extra:
        parser.exit(
            EXIT_BAD_INPUT,
            usage_error(_prog(args), f"unrecognized arguments: {' '.join(extra)}") + "\n",
        )
    if not hasattr(args, "func"):
        parser.print_help()
        return 0
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print("gonio: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except (GonioError, DriverError) as exc:
        print(f"gonio: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        # A path the kernel refuses where no loader expected it (a name too long, say):
        # still one line about that path.
        if exc.filename is None:
            raise
        print(f"gonio: error: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _broken_pipe() -> int:
    """The reader closed stdout: say nothing (as Unix tools)."""
    _stdout_to_devnull()
    return EXIT_BROKEN_PIPE


def _stdout_to_devnull() -> None:
    """Point stdout at /dev/null so that Python's own flush at exit does not print
    "Exception ignored …" about what is still in its buffer."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

__all__ = ["main"]
