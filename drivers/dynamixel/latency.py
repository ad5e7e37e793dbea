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


def adapter_latency_ms(port: str) -> float | None:
    """The USB-serial adapter's latency timer in ms, from sysfs (Linux), or None."""
    try:
        name = Path(os.path.realpath(port)).name
    except OSError:
        return None
    if not re.fullmatch(r"tty(USB|ACM)\d+", name):
        return None
    sysfs = Path("/sys/bus/usb-serial/devices") / name / "latency_timer"
    try:
        return float(sysfs.read_text().strip())
    except (OSError, ValueError):
        return None
