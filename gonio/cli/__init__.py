"""The ``gonio`` command line: one parser, one subcommand per job (presentation only:
parsing, printing, exit codes; the work is done by the domain packages).

Subcommand modules are imported only when their command runs, so ``gonio --help`` does
not pay for scipy or the simulator. Errors a user can cause (``GonioError``, and
``DriverError`` from the hardware layer) become one line on stderr and exit code 2;
anything else is a bug and keeps its traceback. Ctrl-C exits with code 130 and one line.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from drivers.base import DriverError
from gonio import __version__
from gonio.errors import GonioError

#: name → (module with ``add_parser(sub, help_)``, the command's one-line help: the only
#: copy, shown by ``gonio --help`` and passed to the module when it builds its parser).
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": (
        "gonio.cli.demo",
        "the parametrization and lobe tables (the main job is make demo: gonio acquire)",
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
    "info": ("gonio.cli.info", "what a run file holds: progress, time, faults, calibration"),
    "motors": ("gonio.cli.motors", "look at a Dynamixel bus: scan, status, reboot"),
}


def _command_of(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line (the first word not an option)."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (all of them if ``"*"``)."""
    parser = argparse.ArgumentParser(
        prog="gonio",
        description="A virtual gonioreflectometer with a hardware driver layer.",
    )
    parser.add_argument("--version", action="version", version=f"gonio {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in COMMANDS.items():
        if command in (name, "*"):
            importlib.import_module(module).add_parser(sub, help_)
        else:
            sub.add_parser(name, help=help_, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(_command_of(argv))
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 0
    try:
        return int(args.func(args))
    except KeyboardInterrupt:
        print("gonio: interrupted", file=sys.stderr)
        return 130
    except (GonioError, DriverError) as exc:
        print(f"gonio: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
