"""Bus hygiene, checked before the first move: what users of Dynamixel buses trip over.

`check_bus` looks at a port and the motors of its axes and returns one `Finding` a line:

- the **port**: it exists and this user may read and write it (else a *problem* naming
  the port's group, ``dialout`` on most distributions, and how to join it);
- the USB adapter's **latency timer** (Linux sysfs, `drivers.dynamixel.latency`): above
  1 ms a *warning* with the one-line fix and the udev rule that keeps it; on a port
  without one (a pty, a ``ttyACM`` device, a non-FTDI adapter) a line saying it does not
  apply. Never a problem: a slow adapter slows a run, it does not break it;
- every axis's **motor**: it answers at the bus rate with the model number and firmware
  version the axis expects (`AxisConfig.model`, ``firmware``; None: any);
- its **Status Return Level** is 2 (the driver waits for the status of every WRITE and
  REBOOT: at 1 they never come, at 0 not even a READ is answered; it is a RAM item, so
  a reboot restores the default 2);
- its **Return Delay Time** fits the driver's reply timeouts: the motors of one
  SYNC_READ answer one after another, each after its delay, and together they must fit
  in what the timeout leaves beyond the wire time and the adapter's latency
  (`drivers.dynamixel.latency.return_delay_budget_us`): at least the SDK's fixed 2 ms,
  shared by the N motors (500 µs each, the factory default, for 4 motors).

A *problem* blocks a hardware run; each names the motor (ID and axis) and the fix. The
checks send PING and READ only: nothing is written, nothing moves.
"""

from __future__ import annotations

import getpass
import grp
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import item
from drivers.dynamixel.latency import (
    SYSFS_USB_SERIAL,
    UDEV_RULE,
    assumed_adapter_ms,
    latency_timer_file,
    return_delay_budget_us,
    usb_serial_name,
)
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.models import MODEL_NAMES as MODELS
from drivers.errors import CommError, DriverError

Level = Literal["ok", "n/a", "warning", "problem"]
#: The latency timer (ms) above which the adapter gets a warning.
MAX_LATENCY_MS = 1.0
#: The Status Return Level the driver needs: every instruction answered.
STATUS_RETURN_LEVEL = 2
#: Microseconds per unit of the Return Delay Time register.
US_PER_RETURN_DELAY_UNIT = 2
#: The rounds of READ, each after a PING, a motor must leave unanswered (no status back,
#: not even late) to be taken as at Status Return Level 0.
READ_ROUNDS = 3
#: Where the udev rule goes.
UDEV_FILE = "/etc/udev/rules.d/99-dynamixel.rules"


@dataclass(frozen=True)
class Finding:
    """One line of the check: ``level`` and the text (``problem`` blocks a run)."""

    level: Level
    text: str

    def __str__(self) -> str:
        return self.text if self.level == "ok" else f"{self.level}: {self.text}"


def blocking(findings: Sequence[Finding]) -> list[Finding]:
    """The findings that block a hardware run."""
    return [f for f in findings if f.level == "problem"]


def latency_finding(port: str, sysfs: Path = SYSFS_USB_SERIAL) -> Finding:
    """The adapter's latency timer: ok at ≤ 1 ms, a warning above, n/a without one."""
    name = usb_serial_name(port)
    if name is None:
        return Finding("n/a", f"{port}: latency timer does not apply (not a USB-serial adapter)")
    path = latency_timer_file(port, sysfs)
    if path is None:
        return Finding("n/a", f"{port} ({name}): no latency timer (not an FTDI adapter)")
    try:
        value = float(path.read_text().strip())
    except (OSError, ValueError) as exc:
        return Finding("warning", f"{port}: cannot read {path} ({exc}); the latency is unknown")
    if value <= MAX_LATENCY_MS:
        return Finding("ok", f"{port}: USB latency timer {value:g} ms")
    return Finding(
        "warning",
        f"{port}: the USB adapter's latency timer is {value:g} ms (every status waits up "
        f"to that long; 1 ms is enough): echo 1 | sudo tee {path} ; to keep it, put "
        f"{UDEV_RULE} in {UDEV_FILE}",
    )


def access_finding(port: str, access: Callable[[str, int], bool] = os.access) -> Finding:
    """The port exists and this user may read and write it (``access``: `os.access`)."""
    if not os.path.exists(port):
        return Finding(
            "problem",
            f"{port} does not exist: is the USB adapter plugged in?",
        )
    if access(port, os.R_OK | os.W_OK):
        return Finding("ok", f"{port}: readable and writable")
    try:
        group = grp.getgrgid(os.stat(port).st_gid).gr_name
    except (KeyError, OSError):
        group = "dialout"
    return Finding(
        "problem",
        f"{port}: {getpass.getuser()} may not read and write it (group {group}): "
        f"sudo usermod -aG {group} $USER, then log out and in",
    )


@dataclass(frozen=True)
class Expected:
    """What one motor must be: its ID, its axis (None: a motor of no rig), and the model
    number and firmware version it must answer with (None: any)."""

    motor_id: int
    axis: str | None = None
    model: int | None = None
    firmware: int | None = None

    @classmethod
    def of(cls, axis: AxisConfig) -> Expected:
        return cls(axis.motor_id, axis.name, axis.model, axis.firmware)


def _model_name(number: int) -> str:
    name = MODELS.get(number)
    return f"{name} (model number {number})" if name else f"model number {number}"


def _status_registers(link: DynamixelLink, motor_id: int) -> tuple[int, int, int] | None:
    """(Firmware Version, Status Return Level, Return Delay Time) of a motor that answered
    PING; None when READ went unanswered `READ_ROUNDS` times, each after a PING, and no
    status of it came back even late (a motor at Status Return Level 0 answers every PING
    and no READ). A host too loaded to take a reply in time misses some of either: a
    READ whose status came only past every attempt's timeout (the link's syncs discarded
    it) is asked again, and after the last round its `CommError` propagates."""
    names = ("firmware_version", "status_return_level", "return_delay_time")
    discarded = link.late_counts.discarded
    for round_ in range(READ_ROUNDS):
        try:
            if round_:
                link.ping(motor_id)
            firmware, level, delay = (link.read(motor_id, n, alerts=False) for n in names)
        except CommError:
            if round_ == READ_ROUNDS - 1 and link.late_counts.discarded != discarded:
                raise
            continue
        return firmware, level, delay
    return None


def motor_findings(
    link: DynamixelLink, axes: Sequence[Expected], adapter_ms: float
) -> list[Finding]:
    """Model, firmware, Status Return Level and Return Delay Time of each motor, over an
    open ``link`` (PING and READ only); ``adapter_ms``: the adapter latency the run's
    link counts with (`drivers.dynamixel.latency.assumed_adapter_ms`)."""
    out: list[Finding] = []
    budget_us = return_delay_budget_us(len(axes), link.baud, adapter_ms)
    limit = int(budget_us // US_PER_RETURN_DELAY_UNIT)
    port, baud = link.port_name, link.baud
    for axis in axes:
        who = link.who(axis.motor_id)  # the link names the rig's axes
        field = f"axes.{axis.axis or '<axis>'}"
        try:
            model = link.ping(axis.motor_id)
        except DriverError:
            out.append(
                Finding(
                    "problem",
                    f"{who} does not answer on {port} at {baud} baud: check its power, "
                    f"wiring, ID and rate (gonio motors scan --port {port})",
                )
            )
            continue
        first = len(out)
        if axis.model is not None and model != axis.model:
            out.append(
                Finding(
                    "problem",
                    f"{who} is {_model_name(model)}; the rig file expects "
                    f"{_model_name(axis.model)}: connect the right motor, or correct "
                    f"{field}.motor_model",
                )
            )
        elif axis.model is None and model not in MODELS:
            out.append(
                Finding(
                    "warning",
                    f"{who} is {_model_name(model)}, not an X-series model the driver knows "
                    f"({', '.join(MODELS.values())}): its control table may differ; give "
                    f"{field}.motor_model: {model} to accept it",
                )
            )
        registers = _status_registers(link, axis.motor_id)
        if registers is None:
            out.append(
                Finding(
                    "problem",
                    f"{who} answers PING but not READ ({READ_ROUNDS} times, each after a "
                    f"PING it answered): its Status Return Level is 0; the "
                    f"driver needs {STATUS_RETURN_LEVEL}: reboot it (gonio motors reboot "
                    f"--port {port} --ids {axis.motor_id}) to restore it",
                )
            )
            continue
        firmware, level, delay = registers
        if axis.firmware is not None and firmware != axis.firmware:
            out.append(
                Finding(
                    "problem",
                    f"{who} runs firmware {firmware}; the rig file expects {axis.firmware}: "
                    "update it (ROBOTIS Dynamixel Wizard, firmware update) or correct "
                    f"{field}.motor_firmware",
                )
            )
        if level != STATUS_RETURN_LEVEL:
            address = item("status_return_level").address
            out.append(
                Finding(
                    "problem",
                    f"{who} has Status Return Level {level}: the driver needs "
                    f"{STATUS_RETURN_LEVEL} (a status for every instruction; at {level} its "
                    f"writes go unanswered): reboot it (gonio motors reboot --port {port} "
                    f"--ids {axis.motor_id}) or write {STATUS_RETURN_LEVEL} to address "
                    f"{address}",
                )
            )
        delay_us = delay * US_PER_RETURN_DELAY_UNIT
        if delay_us > budget_us:
            address = item("return_delay_time").address
            out.append(
                Finding(
                    "problem",
                    f"{who} has Return Delay Time {delay} ({delay_us} µs): the driver's reply "
                    f"timeouts leave {budget_us:g} µs to each of the {len(axes)} motors of a "
                    f"poll: with torque off write at most {limit} (0 is fastest) to address "
                    f"{address} (EEPROM), e.g. in the ROBOTIS Dynamixel Wizard",
                )
            )
        if len(out) == first:
            out.append(
                Finding(
                    "ok",
                    f"{who}: {MODELS.get(model, f'model {model}')}, firmware {firmware}, "
                    f"return delay {delay_us} µs, status return level {level}",
                )
            )
    return out


def check_bus(
    port: str,
    baud: int,
    axes: Sequence[AxisConfig],
    *,
    sysfs: Path = SYSFS_USB_SERIAL,
    access: Callable[[str, int], bool] = os.access,
    retries: int = 1,
    latency_ms: float | None = None,
) -> list[Finding]:
    """Every check of the module docstring, in order: the port's access, its latency
    timer, then (if the port opens) each axis's motor. ``sysfs`` and ``access`` are
    injectable for tests; ``latency_ms`` is passed to the link (0 for a pty)."""
    findings = [access_finding(port, access), latency_finding(port, sysfs)]
    if blocking(findings) or not axes:
        return findings
    names = {a.motor_id: a.name for a in axes}
    link = DynamixelLink(
        port, baud, retries=retries, latency_ms=latency_ms, names=names, raise_alerts=False
    )
    try:
        with link:
            adapter_ms = assumed_adapter_ms(port, latency_ms, sysfs)
            findings += motor_findings(link, [Expected.of(a) for a in axes], adapter_ms)
    except CommError as exc:
        findings.append(Finding("problem", str(exc)))
    return findings
