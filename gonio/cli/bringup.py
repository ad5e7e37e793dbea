"""Bring-up at a new rig: `gonio motors move | home | torque | set-id`.

The same safety rules as a run, through the same drivers: a joint angle outside its
axis's limits is refused before the port is even opened (no byte is sent); a move goes
through `DynamixelBus` (goals clamped to the motor's own limits, torque enabled only
holding where the arm is, every axis told to hold on a fault and when the command ends,
the port released, also on Ctrl-C); a move with an axis's torque off is refused (the arm
was released on purpose: `gonio motors torque on` first). `set-id` writes the ID
(EEPROM) only to a motor whose torque it has read back off, after a confirmation, never
to an ID already answering, and pings the new ID afterwards.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Mapping
from pathlib import Path

import dynamixel_sdk as sdk

from drivers.dynamixel import FACTORY_BAUD, AxisConfig
from drivers.dynamixel import MODEL_NAMES as MODELS
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError
from gonio.cli.arguments import finite_degrees, positive_seconds
from gonio.config import ConfigError

#: How long a bring-up move may take to settle by default (s).
DEFAULT_TIMEOUT_S = 30.0
#: Exit code of `set-id` when its question was not answered yes.
EXIT_DECLINED = 1


def motor_id(text: str) -> int:
    """A motor ID (0…252)."""
    if not (text.isascii() and text.isdigit()) or not 0 <= int(text) <= 252:
        raise argparse.ArgumentTypeError(f"a motor ID is a whole number in 0…252, got {text!r}")
    return int(text)


def add_parsers(
    cmds: argparse._SubParsersAction[argparse.ArgumentParser],
    baud_type: Callable[[str], int],
) -> None:
    """The bring-up actions under `gonio motors`."""
    move = cmds.add_parser(
        "move",
        help="move one axis to a joint angle (within the rig's limits), print the read-back",
        description="Move one axis of the rig to a joint angle in degrees (the rig file's "
        "angle: 0 = home), refused before any byte if outside the axis's limits or if the "
        "axis's torque is off; waits until settled and prints the angle read back. Every "
        "axis holds where it is when the command ends.",
    )
    _rig_options(move)
    move.add_argument("--axis", required=True, help="the axis's name in the rig file")
    move.add_argument(
        "--deg", type=finite_degrees, required=True, metavar="X", help="the joint angle (°)"
    )
    _timeout_option(move)
    move.set_defaults(func=cmd_move)

    home = cmds.add_parser(
        "home",
        help="move every axis to the rig's home pose",
        description="Move every axis of the rig to its home pose (joint angle 0, or the "
        "nearest limit), wait until settled and print the angles read back.",
    )
    _rig_options(home)
    _timeout_option(home)
    home.set_defaults(func=cmd_home)

    torque = cmds.add_parser(
        "torque",
        help="turn the rig's motors' torque on (holding where they are) or off",
        description="on: every motor of the rig holds where it is (goal := present "
        "position, then torque on; the rig's limits are written to the motors as a run "
        "does). off: the arms go limp: support them first. Read back either way.",
    )
    torque.add_argument("state", choices=("on", "off"), help="on or off")
    _rig_options(torque)
    torque.set_defaults(func=cmd_torque)

    set_id = cmds.add_parser(
        "set-id",
        help="give a motor a new ID (EEPROM; torque must be off)",
        description="Change a motor's ID from A to B: refused if B already answers or "
        "is outside 0…252, or if the motor's torque is on; asks before writing (--yes "
        "skips the question); pings B afterwards. Connect one motor at a time to be sure "
        "which one you change.",
        exit_codes={
            0: "the ID changed",
            EXIT_DECLINED: "the question was not answered yes: nothing written",
        },
    )
    set_id.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0")
    set_id.add_argument(
        "--from", dest="old", type=motor_id, required=True, metavar="A", help="its present ID"
    )
    set_id.add_argument(
        "--to", dest="new", type=motor_id, required=True, metavar="B", help="its new ID, free"
    )
    set_id.add_argument(
        "--baud", type=baud_type, default=FACTORY_BAUD, help=f"baud rate (default {FACTORY_BAUD})"
    )
    set_id.add_argument("--yes", action="store_true", help="do not ask for confirmation")
    set_id.set_defaults(func=cmd_set_id)


def _rig_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--rig", type=Path, required=True, help="the rig file: port, rate, axes")
    p.add_argument("--port", help="serial port (default: the rig file's)")


def _timeout_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--timeout",
        type=positive_seconds,
        default=DEFAULT_TIMEOUT_S,
        metavar="S",
        help=f"how long to wait for the axes to settle (default {DEFAULT_TIMEOUT_S:g} s)",
    )


def _rig_bus(args: argparse.Namespace) -> tuple[str, int, list[AxisConfig]]:
    from gonio.rig import Rig

    rig = Rig.from_yaml(args.rig)
    return args.port or rig.spec.bus.port, rig.spec.bus.baud, rig.bus_axes()


def _home(args: argparse.Namespace) -> dict[str, float]:
    from gonio.rig import Rig

    rig = Rig.from_yaml(args.rig)
    return {name: float(angle) for name, angle in zip(rig.axes, rig.home, strict=True)}


def _check_limits(axes: list[AxisConfig], targets: Mapping[str, float], rig: Path) -> None:
    """`ConfigError` before the port is opened for a target outside its axis's limits."""
    by_name = {a.name: a for a in axes}
    for name, angle in targets.items():
        axis = by_name.get(name)
        if axis is None:
            raise ConfigError(f"{rig}: no axis {name!r}; the axes are {', '.join(by_name)}")
        if not axis.contains(angle):
            raise ConfigError(
                f"axis {name!r}: {math.degrees(angle):g}° is outside its limits "
                f"[{math.degrees(axis.min_rad):g}°, {math.degrees(axis.max_rad):g}°] "
                f"({rig}); nothing was sent"
            )


def _check_torque_on(port: str, baud: int, axes: list[AxisConfig]) -> None:
    """`DriverError` if an axis's torque is off: the arm was released on purpose."""
    names = {a.motor_id: a.name for a in axes}
    with DynamixelLink(port, baud, retries=1, names=names) as link:
        off = [a for a in axes if not link.read(a.motor_id, "torque_enable")]
    if off:
        which = ", ".join(f"{a.name} (motor {a.motor_id})" for a in off)
        raise DriverError(
            f"torque is off on {which}: turn it on with gonio motors torque on --rig RIG "
            "(the axes then hold where they are); nothing was moved"
        )


def _move(args: argparse.Namespace, targets: Mapping[str, float]) -> int:
    port, baud, axes = _rig_bus(args)
    _check_limits(axes, targets, args.rig)
    _check_torque_on(port, baud, axes)
    by_name = {a.name: a for a in axes}
    with DynamixelBus(port, axes, baud=baud) as bus:
        bus.move_to(targets)
        bus.wait_settled(args.timeout)
        read = bus.positions()
    for name, angle in targets.items():
        print(
            f"axis {name} (motor {by_name[name].motor_id}): at {math.degrees(read[name]):.2f}° "
            f"(asked {math.degrees(angle):g}°)"
        )
    return 0


def cmd_move(args: argparse.Namespace) -> int:
    return _move(args, {args.axis: math.radians(args.deg)})


def cmd_home(args: argparse.Namespace) -> int:
    return _move(args, _home(args))


def cmd_torque(args: argparse.Namespace) -> int:
    port, baud, axes = _rig_bus(args)
    if args.state == "on":
        # Opening the bus sets each goal to the present position, then torque on; the
        # release keeps it on, holding.
        with DynamixelBus(port, axes, baud=baud):
            pass
        for a in axes:
            print(f"axis {a.name} (motor {a.motor_id}): torque on, holding")
        return 0
    names = {a.motor_id: a.name for a in axes}
    with DynamixelLink(port, baud, retries=1, names=names) as link:
        for a in axes:
            link.write(a.motor_id, "torque_enable", 0)
            if link.read(a.motor_id, "torque_enable") != 0:
                raise DriverError(f"{link.who(a.motor_id)} did not turn its torque off")
            print(f"axis {a.name} (motor {a.motor_id}): torque off")
    return 0


def _answers(link: DynamixelLink, motor: int) -> int | None:
    """The model number of ``motor``, or None if nothing answers to that ID."""
    try:
        return link.ping(motor)
    except CommError as exc:
        if exc.result == sdk.COMM_RX_TIMEOUT:
            return None
        raise


def _confirm(question: str) -> bool:
    print(question, end=" ", flush=True)
    try:
        answer = sys.stdin.readline()
    except (OSError, ValueError):
        answer = ""
    if not answer or not sys.stdin.isatty():  # a terminal echoed the answer's newline
        print()
    return answer.strip().lower() in ("y", "yes")


def cmd_set_id(args: argparse.Namespace) -> int:
    old, new = args.old, args.new
    if old == new:
        raise ConfigError(f"set-id: --from and --to are both {old}; nothing to change")
    with DynamixelLink(args.port, args.baud, retries=1) as link:
        model = _answers(link, old)
        if model is None:
            raise DriverError(f"{args.port}: no motor answers as ID {old} at {args.baud} baud")
        taken = _answers(link, new)
        if taken is not None:
            raise ConfigError(
                f"ID {new} is already taken on {args.port} (a {MODELS.get(taken, 'motor')}); "
                "choose a free ID (gonio motors scan lists them); nothing was written"
            )
        if link.read(old, "torque_enable"):
            raise DriverError(
                f"motor {old} has its torque on: its ID (EEPROM) is written only with torque "
                "off (gonio motors torque off, supporting the arm); nothing was written"
            )
        if not args.yes and not _confirm(
            f"change the ID of motor {old} ({MODELS.get(model, 'model ' + str(model))}) "
            f"on {args.port} to {new}? [y/N]"
        ):
            print("nothing changed")
            return EXIT_DECLINED
        link.write(old, "id", new)
        found = _answers(link, new)
    if found is None:
        raise DriverError(f"motor {old} took the write, but nothing answers as ID {new}")
    print(f"motor {old} is now ID {new} ({MODELS.get(found, 'model ' + str(found))})")
    return 0
