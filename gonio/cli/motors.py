"""`gonio motors scan | status | reboot`: look at a Dynamixel bus, with or without a
rig file; `move | home | torque | set-id` bring a new rig up (`gonio.cli.bringup`).

Every command opens the port, does its job through `drivers.dynamixel.link`, and
releases the port; driver errors become one line (see `gonio.cli`). Given ``--rig``,
`status` takes the port, rate and IDs from the rig file (flags still override) and
adds each motor's axis and its joint angle.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from drivers.dynamixel import (
    BAUD_RATES,
    FACTORY_BAUD,
    RAD_PER_TICK,
    AxisConfig,
    hygiene,
)
from drivers.dynamixel import MODEL_NAMES as MODELS
from drivers.dynamixel.latency import assumed_adapter_ms
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError
from gonio.cli import EXIT_BAD_INPUT
from gonio.config import ConfigError

#: The rates `scan` tries by default: factory default first, then the SDK's default.
DEFAULT_SCAN_BAUDS = (FACTORY_BAUD, 1_000_000)
#: Exit code of `scan` when no motor answered, and of `status` when one did not.
EXIT_NO_ANSWER = 1
#: Exit code of `scan` when the bus would block a run (`drivers.dynamixel.hygiene`):
#: the program's code for a device refused.
EXIT_PROBLEM = EXIT_BAD_INPUT


def motor_ids(text: str) -> list[int]:
    """Motor IDs (0…252), listed or ranged: "1,2,5-7" is [1, 2, 5, 6, 7].

    A range with an end missing ("1-") or going down ("4-1") is refused, not read as
    something else."""
    ids: list[int] = []
    for part in text.split(","):
        lo, dash, hi = (w.strip() for w in part.strip().partition("-"))
        if not _number(lo) or (dash and not _number(hi)):
            raise argparse.ArgumentTypeError(f"expected IDs like 1,2,5-7, got {text!r}")
        first, last = int(lo), int(hi if dash else lo)
        if last < first:
            raise argparse.ArgumentTypeError(
                f"the range {part.strip()!r} goes down; write {last}-{first}"
            )
        if last > 252:  # before making the range: "1-99999999999" must not fill memory
            raise argparse.ArgumentTypeError(f"motor IDs must be in 0…252, got {text!r}")
        ids.extend(range(first, last + 1))
    return ids


def _number(word: str) -> bool:
    return word.isascii() and word.isdigit()


def baud_rate(text: str) -> int:
    """A baud rate the motors know (bit/s)."""
    value = int(text) if text.isdigit() else -1
    if value not in BAUD_RATES.values():
        choices = ", ".join(str(b) for b in BAUD_RATES.values())
        raise argparse.ArgumentTypeError(f"baud must be one of {choices}, got {text!r}")
    return value


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    motors = sub.add_parser(
        "motors",
        help=help_,
        description="Look at a Dynamixel bus (scan, status, reboot) and bring a rig up "
        "(move, home, torque, set-id), on the safety rules of a run.",
    )
    cmds = motors.add_subparsers(dest="motors_command", metavar="ACTION", required=True)

    scan = cmds.add_parser(
        "scan",
        help="list the motors answering on a port, and check the bus",
        description="Check the port (this user may open it; the USB adapter's latency "
        "timer), send a broadcast ping at each rate and list the motors that answer: ID, "
        "model and firmware; check that each suits the driver (Status Return Level 2, a "
        "Return Delay Time its timeouts allow). With --rig, also that every axis's motor "
        "answers at the rig's rate as the model and firmware the rig file expects. A "
        "problem that would block a run is one line naming the motor and the fix, and exit "
        "code 2.",
        exit_codes={0: "a motor answered", EXIT_NO_ANSWER: "no motor answered at any rate"},
    )
    scan.add_argument("--rig", type=Path, help="a rig file: its port, rate and axes")
    scan.add_argument("--port", help="serial port, e.g. /dev/ttyUSB0 (required without --rig)")
    scan.add_argument(
        "--baud",
        type=baud_rate,
        action="append",
        help="baud rate to try (repeatable; default the rig's, else "
        f"{' then '.join(map(str, DEFAULT_SCAN_BAUDS))})",
    )
    scan.set_defaults(func=cmd_scan)

    status = cmds.add_parser(
        "status",
        help="positions, temperatures, voltages, error flags",
        description="Read each motor's model, position (ticks and degrees), moving and "
        "torque state, temperature (°C), input voltage (V) and hardware error flags; with "
        "--rig also its axis and joint angle (degrees), marked if outside the axis's limits.",
        exit_codes={
            0: "every motor answered",
            EXIT_NO_ANSWER: "a motor did not answer or answered with an error",
        },
    )
    status.add_argument("--rig", type=Path, help="a rig file: port, rate, IDs and axes")
    status.add_argument("--port", help="serial port (default: the rig file's)")
    status.add_argument("--ids", type=motor_ids, help="e.g. 1,2,3 or 1-4 (default: the rig's)")
    status.add_argument(
        "--baud", type=baud_rate, help=f"baud rate (default: the rig's, else {FACTORY_BAUD})"
    )
    status.set_defaults(func=cmd_status)

    reboot = cmds.add_parser(
        "reboot",
        help="reboot motors (clears hardware errors)",
        description="Reboot each motor, which clears its hardware error flags; its torque "
        "is off afterwards.",
    )
    reboot.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0")
    reboot.add_argument("--ids", type=motor_ids, required=True, help="e.g. 1,2,3 or 1-4")
    reboot.add_argument(
        "--baud", type=baud_rate, default=FACTORY_BAUD, help=f"baud rate (default {FACTORY_BAUD})"
    )
    reboot.set_defaults(func=cmd_reboot)

    from gonio.cli import bringup

    bringup.add_parsers(cmds, baud_rate)


def cmd_scan(args: argparse.Namespace) -> int:
    axes: list[AxisConfig] = []
    port, bauds, rig_baud = args.port, args.baud, None
    if args.rig is not None:
        from gonio.rig import Rig

        rig = Rig.from_yaml(args.rig)
        axes = rig.bus_axes()
        port = port or rig.spec.bus.port
        rig_baud = rig.spec.bus.baud
        bauds = bauds or [rig_baud]
    if port is None:
        raise ConfigError("motors scan: give --port or --rig RIG.yaml")
    access = hygiene.access_finding(port)
    if access.level == "problem":  # nothing more can be checked: one line, exit 2
        raise ConfigError(access.text)
    _show([access, hygiene.latency_finding(port)])
    found_any = problem = False
    names = {a.motor_id: a.name for a in axes}
    for baud in bauds or DEFAULT_SCAN_BAUDS:
        with DynamixelLink(port, baud, retries=1, names=names, raise_alerts=False) as link:
            found = link.scan()
            print(f"{port} at {baud} baud: {len(found)} motor(s)")
            if found:
                found_any = True
                print(f"  {'ID':>3}  {'model':<12} {'number':>6}  firmware")
                for motor_id, (model, firmware) in sorted(found.items()):
                    name = MODELS.get(model, "unknown")
                    print(f"  {motor_id:>3}  {name:<12} {model:>6}  {firmware}")
            # The rig's axes at the rig's rate (a missing one is a problem), else whoever
            # answered, for what the driver needs of any motor.
            expected = [hygiene.Expected.of(a) for a in axes] if baud == rig_baud else []
            expected += [hygiene.Expected(m) for m in sorted(found) if m not in names]
            if expected:
                adapter_ms = assumed_adapter_ms(port)
                checks = hygiene.motor_findings(link, expected, adapter_ms)
                _show(checks, indent="  ")
                problem = problem or bool(hygiene.blocking(checks))
    if not found_any:
        print("no motor answered: check power (the LED blinks once at power-up), wiring, and rate")
        return EXIT_NO_ANSWER
    return EXIT_PROBLEM if problem else 0


def _show(findings: list[hygiene.Finding], indent: str = "") -> None:
    for finding in findings:
        print(f"{indent}{finding.level}: {finding.text}")


def _status_target(args: argparse.Namespace) -> tuple[str, int, list[int], dict[int, AxisConfig]]:
    """(port, baud, IDs, axis of each ID) from the flags and the rig file."""
    axes: dict[int, AxisConfig] = {}
    port, baud, ids = args.port, args.baud, args.ids
    if args.rig is not None:
        from gonio.rig import Rig

        rig = Rig.from_yaml(args.rig)
        axes = {a.motor_id: a for a in rig.bus_axes()}
        port = port or rig.spec.bus.port
        baud = baud or rig.spec.bus.baud
        ids = ids or sorted(axes)
    if port is None or ids is None:
        raise ConfigError("motors status: give --port and --ids, or --rig RIG.yaml")
    return port, baud or FACTORY_BAUD, ids, axes


def cmd_status(args: argparse.Namespace) -> int:
    port, baud, ids, axes = _status_target(args)
    missing = 0
    header = (
        f"{'ID':>3}  {'model':<12} {'position':>9} {'(deg)':>9}  {'moving':>6} "
        f"{'torque':>6} {'temp °C':>7} {'volt V':>6}  errors"
    )
    if axes:
        header += f"  {'axis':<20} {'joint (deg)':>11}"
    with DynamixelLink(port, baud, retries=1, raise_alerts=False) as link:
        print(header)
        for motor_id in ids:
            try:
                model = MODELS.get(link.ping(motor_id), "unknown")
                errors = link.hardware_error(motor_id)
                ticks = link.read(motor_id, "present_position")
                row = (
                    f"{motor_id:>3}  {model:<12} {ticks:>9} "
                    f"{math.degrees(ticks * RAD_PER_TICK):>9.2f}  "
                    f"{'yes' if link.read(motor_id, 'moving') else 'no':>6} "
                    f"{'on' if link.read(motor_id, 'torque_enable') else 'off':>6} "
                    f"{link.read(motor_id, 'present_temperature'):>7} "
                    f"{link.read(motor_id, 'present_input_voltage') / 10:>6.1f}  "
                    f"{', '.join(errors) or 'none'}"
                )
                if motor_id in axes:
                    axis = axes[motor_id]
                    joint = math.degrees(axis.to_rad(ticks))
                    inside = "" if axis.contains(axis.to_rad(ticks)) else "  OUTSIDE LIMITS"
                    row += f"  {axis.name:<20} {joint:>11.2f}{inside}"
                elif axes:
                    row += f"  {'(not in the rig)':<20}"
            except CommError:
                missing += 1
                row = f"{motor_id:>3}  no answer"
            except DriverError as exc:  # e.g. a status error: show it, keep going
                missing += 1
                row = f"{motor_id:>3}  {exc}"
            print(row)
    return EXIT_NO_ANSWER if missing else 0


def cmd_reboot(args: argparse.Namespace) -> int:
    with DynamixelLink(args.port, args.baud, retries=1) as link:
        for motor_id in args.ids:
            link.reboot(motor_id)
            print(f"motor {motor_id} rebooted")
    return 0
