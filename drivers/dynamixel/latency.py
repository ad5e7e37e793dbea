"""The latency budget of a Dynamixel port (`drivers.dynamixel.link`).

Latency: the SDK waits 2 × LATENCY_TIMER + 2 ms plus the wire time of the *reply* for a
status packet. That budget must cover the USB adapter's own latency timer (FTDI
default 16 ms; 1 ms after the udev rule in docs/reference/hardware.md) and also what the SDK
leaves out: the wire time of the instruction itself and of a packet without reply
still leaving the adapter before it (a SYNC_WRITE of goals just before a SYNC_READ
poll: 6 ms at 57 600 baud). The link sets its port's latency timer to the adapter's
latency (read from sysfs when it can, else the SDK's conservative 16 ms) plus half the
wire time of `OUTBOUND_MARGIN_BYTES` at the bus rate. The SDK keeps LATENCY_TIMER as a
process-wide global of ``dynamixel_sdk.port_handler``; the link neither reads nor
writes it (each port has its own), so two buses with different rates or adapters
never change each other's timeouts.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

DEFAULT_LATENCY_MS = 16.0  # the SDK's own default, safe for an unconfigured FTDI adapter
#: Outbound bytes the SDK's reply timeout does not count: the instruction and a
#: preceding packet without reply (a 4-axis SYNC_READ is 18 bytes, a 4-axis SYNC_WRITE
#: of goals 34), with room for larger buses.
OUTBOUND_MARGIN_BYTES = 96


def sdk_latency_timer(adapter_ms: float, baud: int) -> float:
    """The latency timer (ms) for the SDK's reply timeouts: the adapter's latency plus
    half the wire time of `OUTBOUND_MARGIN_BYTES` (the SDK doubles it), at least 1 ms."""
    return max(1.0, adapter_ms + 0.5 * 1000.0 * 10 * OUTBOUND_MARGIN_BYTES / baud)


#: Where Linux lists its USB-serial ports (``ttyUSB<n>``), each with its driver and, for
#: FTDI adapters, their ``latency_timer`` (ms).
SYSFS_USB_SERIAL = Path("/sys/bus/usb-serial/devices")
#: The SDK's fixed margin in every reply timeout (ms): 2 × LATENCY_TIMER + this.
SDK_MARGIN_MS = 2.0
#: The udev rule that sets every FTDI adapter's latency timer to 1 ms when it is plugged in.
UDEV_RULE = 'ACTION=="add", SUBSYSTEM=="usb-serial", DRIVER=="ftdi_sio", ATTR{latency_timer}="1"'


def usb_serial_name(port: str) -> str | None:
    """The kernel name (``ttyUSB0``) of ``port`` after symlinks (``/dev/serial/by-id/…``),
    or None when it is no USB-serial device (a pty, a ``ttyACM`` CDC device, a file)."""
    try:
        name = Path(os.path.realpath(port)).name
    except OSError:
        return None
    return name if re.fullmatch(r"ttyUSB\d+", name) else None


def latency_timer_file(port: str, sysfs: Path = SYSFS_USB_SERIAL) -> Path | None:
    """The sysfs file of ``port``'s adapter latency timer, or None when it has none (not a
    USB-serial port, or an adapter without one: only FTDI's ``ftdi_sio`` has it)."""
    name = usb_serial_name(port)
    if name is None:
        return None
    path = sysfs / name / "latency_timer"
    return path if path.is_file() else None


def adapter_latency_ms(port: str, sysfs: Path = SYSFS_USB_SERIAL) -> float | None:
    """The USB-serial adapter's latency timer in ms, from sysfs (Linux), or None."""
    path = latency_timer_file(port, sysfs)
    if path is None:
        return None
    try:
        return float(path.read_text().strip())
    except (OSError, ValueError):
        return None


def assumed_adapter_ms(
    port: str, latency_ms: float | None = None, sysfs: Path = SYSFS_USB_SERIAL
) -> float:
    """The adapter latency (ms) a link on ``port`` counts with: ``latency_ms`` if given,
    else the adapter's latency timer from sysfs, else `DEFAULT_LATENCY_MS`."""
    if latency_ms is not None:
        return latency_ms
    found = adapter_latency_ms(port, sysfs)
    return DEFAULT_LATENCY_MS if found is None else found


def return_delay_budget_us(motors: int, baud: int, adapter_ms: float) -> float:
    """The most Return Delay Time (µs) each of ``motors`` motors may take at ``baud``
    behind an adapter of latency ``adapter_ms`` (what the link counts with).

    The SDK waits for a status the reply's wire time + 2 × LATENCY_TIMER + 2 ms, with
    LATENCY_TIMER = `sdk_latency_timer`. Beyond the reply's own bytes, that wait must
    hold the outbound wire time the timeout leaves out (`OUTBOUND_MARGIN_BYTES`) and the
    adapter's latency; the rest is what the return delays may take, and a SYNC_READ's
    motors answer one after another, each after its own delay, so they share it: at
    least the SDK's 2 ms whatever the adapter (on a pty with ``adapter_ms`` 0 at
    57 600 baud, exactly that).
    """
    outbound_ms = 1000.0 * 10 * OUTBOUND_MARGIN_BYTES / baud
    slack_ms = 2.0 * sdk_latency_timer(adapter_ms, baud) + SDK_MARGIN_MS - outbound_ms - adapter_ms
    return 1000.0 * slack_ms / max(1, motors)
