"""The ``gonio`` command line: one parser, one subcommand per job.

Errors a user can cause (``GonioError``, and ``DriverError`` from the hardware layer)
become one line on stderr and exit code 2; anything else is a bug and keeps its
traceback. Ctrl-C exits with code 130 and one line.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from drivers.base import DriverError
from gonio import __version__, motors_cli, plan_cli, simulate_cli
from gonio.errors import GonioError


def _cmd_demo(args: argparse.Namespace) -> int:
    from gonio.demo import render

    print(render())
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gonio",
        description="A virtual gonioreflectometer with a hardware driver layer.",
    )
    parser.add_argument("--version", action="version", version=f"gonio {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser(
        "demo",
        help="print the parametrizations on named direction pairs and the seed-003 lobe table",
        description="The most complete end-to-end path that exists: the four "
        "parametrizations' coordinates and round-trip errors for named direction pairs, "
        "and the seed-003 lobe comparison.",
    )
    demo.set_defaults(func=_cmd_demo)
    plan_cli.add_parser(sub)
    simulate_cli.add_parser(sub)
    motors_cli.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
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
