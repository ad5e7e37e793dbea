"""The Dynamixel bus in numbers: round trips against the emulator over a real pty.

For 4 axes at 57 600 and 1 000 000 baud, with the emulator timing bytes on the wire and
the motors' default 500 µs return delay: the round trip of one SYNC_READ poll (Moving …
Present Position), of a hold-in-place step (move to where the axes are + settle: the
communication cost of one acquisition step with no motion), and of a small move
(0.02 rad, 13 ticks) and settle; bytes on the serial line per step; and the theoretical
minimum (bytes × 10 bits / baud + return delays). Prints a markdown table.
Run: .venv/bin/python benchmarks/bus.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from drivers.dynamixel import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from sim.peers.dynamixel.emulator import DxlEmulator

AXES = [
    AxisConfig(
        f"axis{i}",
        i,
        -1.0,
        1.0,
        zero_offset_rad=-math.pi,
        profile_velocity_rad_s=4.0,
        profile_acceleration_rad_s2=40.0,
    )
    for i in range(1, 5)
]
RETURN_DELAY_S = 250 * 2e-6  # the motors' default Return Delay Time
#: Data bytes of one poll per motor: Moving (122) … Present Position (132-135).
POLL_DATA = 14


def sync_read_bytes(motors: int) -> int:
    """A SYNC_READ instruction: header 4, ID, LEN 2, INST, address 2, length 2, one byte
    per motor ID, CRC 2 (no stuffing: none of these bytes can form FF FF FD)."""
    return 4 + 1 + 2 + 1 + 2 + 2 + motors + 2


def status_bytes(data: int) -> int:
    """A status packet: header 4, ID, LEN 2, 0x55, ERR, the data, CRC 2 (unstuffed)."""
    return 4 + 1 + 2 + 1 + 1 + data + 2


#: Bytes on the line for one poll of the 4 axes: 18 + 4 × 25 = 118.
POLL_BYTES = sync_read_bytes(len(AXES)) + len(AXES) * status_bytes(POLL_DATA)


def timed(fn, repeat: int) -> float:
    samples = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t)
    return statistics.median(samples)


def measure(baud: int, repeat: int) -> dict[str, float]:
    with (
        DxlEmulator(ids=range(1, 5), baud=baud) as emu,
        DynamixelBus(emu.path, AXES, baud=baud, latency_ms=4.0) as bus,
    ):
        poll = timed(bus.positions, repeat)
        emu.reset_stats()
        here = bus.positions()
        stats = emu.stats
        if stats.bytes_in + stats.bytes_out != POLL_BYTES:
            raise AssertionError(f"a poll moved {stats.bytes_in + stats.bytes_out} bytes")

        emu.reset_stats()
        hold = timed(lambda: (bus.move_to(here), bus.wait_settled(2.0)), repeat)
        stats = emu.stats
        hold_bytes = (stats.bytes_in + stats.bytes_out) / repeat
        hold_packets_out = stats.packets_out / repeat

        toggle = [0.02]

        def small_move() -> None:
            toggle[0] = -toggle[0]
            bus.move_to(dict.fromkeys(bus.axes, toggle[0]))
            bus.wait_settled(2.0)

        small = timed(small_move, max(10, repeat // 5))
    return {
        "poll_ms": poll * 1e3,
        "poll_min_ms": (POLL_BYTES * 10 / baud + len(AXES) * RETURN_DELAY_S) * 1e3,
        "poll_bytes": POLL_BYTES,
        "hold_ms": hold * 1e3,
        "hold_bytes": hold_bytes,
        "hold_min_ms": (hold_bytes * 10 / baud + hold_packets_out * RETURN_DELAY_S) * 1e3,
        "small_ms": small * 1e3,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=100)
    args = ap.parse_args()
    rows = {baud: measure(baud, args.repeat) for baud in (57_600, 1_000_000)}
    print(f"machine: {describe()}")
    print(f"4 axes, emulator with wire time and 500 µs return delay, median of {args.repeat}\n")
    lines = [
        ("SYNC_READ poll (Moving … Present Position), ms", "poll_ms", ".2f"),
        ("poll: theoretical minimum (bytes × 10 / baud + return delays), ms", "poll_min_ms", ".2f"),
        ("poll: bytes on the line", "poll_bytes", ".0f"),
        ("hold step (SYNC_WRITE of goals + settle polls), ms", "hold_ms", ".2f"),
        ("hold step: theoretical minimum, ms", "hold_min_ms", ".2f"),
        ("hold step: bytes on the line", "hold_bytes", ".0f"),
        ("move 0.02 rad and settle, ms", "small_ms", ".1f"),
    ]
    two_rate_table(rows, lines)


def two_rate_table(rows: dict[int, dict[str, float]], lines: list[tuple[str, str, str]]) -> None:
    """Print a markdown table of ``lines`` (label, key in ``rows``, format) at the two
    baud rates, 57 600 and 1 000 000."""
    print("| | 57 600 baud | 1 000 000 baud |")
    print("| --- | ---: | ---: |")
    for label, key, fmt in lines:
        a, b = rows[57_600][key], rows[1_000_000][key]
        print(f"| {label} | {a:{fmt}} | {b:{fmt}} |")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The Dynamixel bus: round trips on the emulator")
