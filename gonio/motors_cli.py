"""`gonio motors scan | status | reboot`: look at a Dynamixel bus without a rig file.

Every command opens the port, does its job through `drivers.dynamixel.link`, and
releases the port; driver errors become one line (see `gonio.cli`).
"""

from __future__ import annotations

import argparse
import math

from drivers.base import CommError, DriverError
from drivers.dynamixel.control_table import BAUD_RATES, MODELS, RAD_PER_TICK
from drivers.dynamixel.link import DynamixelLink

#: The rates `scan` tries by default: factory default first, then the SDK's default.
DEFAULT_SCAN_BAUDS = (57_600, 1_000_000)


def motor_ids(text: str) -> list[int]:
    """Parse "1,2,5-7" into [1, 2, 5, 6, 7] (IDs 0…252)."""
    ids: list[int] = []
    try:
        for part in text.split(","):
            lo, _, hi = part.strip().partition("-")
            first, last = int(lo), int(hi or lo)
            ids.extend(range(first, last + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected IDs like 1,2,5-7, got {text!r}") from None
    bad = [i for i in ids if not 0 <= i <= 252]
    if not ids or bad:
        raise argparse.ArgumentTypeError(f"motor IDs must be in 0…252, got {text!r}")
    return ids


def baud_rate(text: str) -> int:
    value = int(text) if text.isdigit() else -1
    if value not in BAUD_RATES.values():
        choices = ", ".join(str(b) for b in BAUD_RATES.values())
        raise argparse.ArgumentTypeError(f"baud must be one of {choices}, got {text!r}")
    return value


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    motors = sub.add_parser("motors", help="scan, inspect and reboot Dynamixel motors")
    cmds = motors.add_subparsers(dest="motors_command", metavar="ACTION", required=True)

    scan = cmds.add_parser("scan", help="list the motors answering on a port")
    scan.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0")
    scan.add_argument(
        "--baud",
        type=baud_rate,
        action="append",
        help=f"rate to try (repeatable; default {', '.join(map(str, DEFAULT_SCAN_BAUDS))})",
    )
    scan.set_defaults(func=cmd_scan)

    status = cmds.add_parser("status", help="positions, temperatures, voltages, error flags")
    status.add_argument("--port", required=True)
    status.add_argument("--ids", type=motor_ids, required=True, help="e.g. 1,2,3 or 1-4")
    status.add_argument("--baud", type=baud_rate, default=57_600)
    status.set_defaults(func=cmd_status)

    reboot = cmds.add_parser("reboot", help="reboot motors (clears hardware errors)")
    reboot.add_argument("--port", required=True)
    reboot.add_argument("--ids", type=motor_ids, required=True)
    reboot.add_argument("--baud", type=baud_rate, default=57_600)
    reboot.set_defaults(func=cmd_reboot)


def cmd_scan(args: argparse.Namespace) -> int:
    found_any = False
    for baud in args.baud or DEFAULT_SCAN_BAUDS:
        with DynamixelLink(args.port, baud, retries=0) as link:
            found = link.scan()
        print(f"{args.port} at {baud} baud: {len(found)} motor(s)")
        if found:
            found_any = True
            print(f"  {'ID':>3}  {'model':<12} {'number':>6}  firmware")
            for motor_id, (model, firmware) in sorted(found.items()):
                name = MODELS.get(model, "unknown")
                print(f"  {motor_id:>3}  {name:<12} {model:>6}  {firmware}")
    if not found_any:
        print("no motor answered: check power (the LED blinks once at power-up), wiring, and rate")
        return 1
    return 0


def cmd_status(args: argparse.Namespace) -> int:
    missing = 0
    header = (
        f"{'ID':>3}  {'model':<12} {'position':>9} {'(deg)':>9}  {'moving':>6} "
        f"{'torque':>6} {'temp °C':>7} {'volt V':>6}  errors"
    )
    with DynamixelLink(args.port, args.baud, retries=1, raise_alerts=False) as link:
        print(header)
        for motor_id in args.ids:
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
            except CommError:
                missing += 1
                row = f"{motor_id:>3}  no answer"
            except DriverError as exc:  # e.g. a status error: show it, keep going
                missing += 1
                row = f"{motor_id:>3}  {exc}"
            print(row)
    return 1 if missing else 0


def cmd_reboot(args: argparse.Namespace) -> int:
    with DynamixelLink(args.port, args.baud, retries=1) as link:
        for motor_id in args.ids:
            link.reboot(motor_id)
            print(f"motor {motor_id} rebooted")
    return 0
