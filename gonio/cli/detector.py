"""`gonio detector check-stream --rig RIG.yaml`: qualify a serial photometer for fly
plans. It streams from the rig's detector, prints a verdict per requirement with the
measured numbers and writes the verdict beside the rig file (``RIG.stream-check.yaml``),
where `gonio acquire` reads it before a fly plan runs on the hardware
(`gonio.workflows.stream_check`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from gonio.cli.arguments import positive, positive_seconds

#: Exit code of a check that ran and found a requirement failed (the verdict is written).
EXIT_FAILED = 1


def starts(text: str) -> int:
    """A number of streams to start: a whole number ≥ 2."""
    value = int(text) if text.isascii() and text.isdigit() else -1
    if value < 2:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 2, got {text!r}")
    return value


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    detector = sub.add_parser(
        "detector",
        help=help_,
        description="Look at the rig's detector: check-stream qualifies a serial photometer "
        "for fly plans on the hardware.",
    )
    cmds = detector.add_subparsers(dest="detector_command", metavar="ACTION", required=True)
    check = cmds.add_parser(
        "check-stream",
        help="measure what a fly scan needs of a streaming serial detector; write the verdict",
        description="Stream from the rig's serial detector and measure what a fly scan needs "
        "of it (docs/reference/serial_detector.md): the stop acknowledged after the last "
        "line, the first window begun on the start command, a steady rate, timestamps, the "
        "latency, the lines' wire time, a query answered afterwards. Prints a verdict per "
        "requirement and writes them beside the rig file (RIG.stream-check.yaml), where "
        "gonio acquire reads it: a passing verdict for the rig's detector configuration "
        "lets fly plans run on the hardware at up to the rate checked.",
        exit_codes={
            0: "every requirement passed (the verdict is written)",
            EXIT_FAILED: "a requirement failed (the verdict is written; fly stays refused)",
            2: "bad input: the rig, an option or the port refused, in one line; nothing written",
        },
    )
    check.add_argument("--rig", type=Path, required=True, help="the rig file (RIG.yaml)")
    check.add_argument("--port", help="the serial port to use instead of the rig file's")
    check.add_argument(
        "--rate",
        type=positive,
        metavar="HZ",
        help="the rate to stream at (default: the rig's stream.max_rate_hz, which "
        "qualifies every lower rate)",
    )
    check.add_argument(
        "--duration",
        type=positive_seconds,
        default=2.0,
        metavar="S",
        help="how long the first stream lasts (default 2 s; the others are short)",
    )
    check.add_argument(
        "--starts", type=starts, default=5, help="how many streams to start (default 5)"
    )
    check.add_argument(
        "--identify",
        metavar="COMMAND",
        help="a command whose one-line answer names the instrument (ID?, *IDN?), recorded",
    )
    check.add_argument(
        "-o",
        "--output",
        type=Path,
        help="where to write the verdict (default RIG.stream-check.yaml beside the rig file, "
        "the only place gonio acquire reads it)",
    )
    check.set_defaults(func=cmd_check_stream)


def cmd_check_stream(args: argparse.Namespace) -> int:
    from gonio.output import reserve_output
    from gonio.rig import Rig
    from gonio.workflows import check_stream, verdict_path

    rig = Rig.from_yaml(args.rig)
    output = args.output or verdict_path(args.rig)
    with reserve_output(output, "-o", inputs=[args.rig]) as out:
        verdict = check_stream(
            rig,
            port=args.port,
            rate_hz=args.rate,
            duration_s=args.duration,
            starts=args.starts,
            identify=args.identify,
        )
        out.write_bytes(verdict.to_yaml().encode("utf-8"))
    who = verdict.port + (f" ({verdict.identity})" if verdict.identity else "")
    print(
        f"stream check of {who} at {verdict.rate_hz:g} Hz, integration "
        f"{verdict.integration_s * 1e3:g} ms, {verdict.starts} starts:"
    )
    width = max(len(r.name) for r in verdict.requirements)
    for r in verdict.requirements:
        print(f"  {'pass' if r.passed else 'FAIL'}  {r.name:<{width}}  {r.summary}")
    if verdict.passed:
        print(
            f"passed: fly plans may run on this rig's hardware at up to {verdict.rate_hz:g} Hz "
            f"(verdict: {output})"
        )
        return 0
    names = ", ".join(r.name for r in verdict.failed)
    print(f"failed: {names}; fly plans stay refused on the hardware (verdict: {output})")
    return EXIT_FAILED
