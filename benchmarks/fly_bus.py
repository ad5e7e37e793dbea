"""Polling the Dynamixel bus during a sweep: polls per second on the rehearsal path against
the bus's theoretical rate.

For 4 axes at 57 600 and 1 000 000 baud, `DynamixelBus` drives the byte-level emulator
over a real pty in real time (bytes timed on the wire, the motors' default 500 µs
return delay): each sweep moves every axis 0.6 rad at 1 rad/s (`DynamixelBus.sweep`)
and the host calls `poll_positions` back to back until the motion has arrived. Polls per
second are polls / (last reply − first request); the theoretical rate is one over the
shortest poll: the bytes of one SYNC_READ of Present Position (instruction and 4 status
packets) × 10 bits / baud, plus the 4 return delays. Each polled position is compared
with the emulator's own trajectory at the middle of its poll (in encoder ticks, and as a
fraction of the bound one tick + v · (reply − request)). The same sweeps are polled once
more with the emulator in a process of its own (as ``python -m sim.dynamixel.emulator``
serves a bus), where the host's polling loop does not share an interpreter with the
motors. Prints a markdown table.
Run: .venv/bin/python benchmarks/fly_bus.py [--sweeps N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe
from bus import AXES, two_rate_table  # the four axes benchmarks/bus.py times

from drivers.dynamixel import poll_bytes, poll_seconds
from drivers.dynamixel.bus import DynamixelBus
from drivers.values import StampedPositions
from sim.peers.dynamixel.emulator import DxlEmulator

SPEED = 1.0  # rad/s
STROKE = 0.6  # rad
TICK = 2 * math.pi / 4096
ROOT = Path(__file__).resolve().parents[1]


def measure(baud: int, sweeps: int) -> dict[str, float]:
    """One emulator and bus at ``baud``: ``sweeps`` sweeps there and back, polled."""
    polls: list[StampedPositions] = []
    errors: list[float] = []  # ticks
    used: list[float] = []  # error / bound
    rate_spans: list[tuple[int, float]] = []
    with (
        DxlEmulator(ids=range(1, 5), baud=baud) as emu,
        DynamixelBus(emu.path, AXES, baud=baud, latency_ms=4.0) as bus,
    ):
        motors = {a.name: emu.motors[a.motor_id] for a in AXES}
        by_name = {a.name: a for a in AXES}
        bus.move_to(dict.fromkeys(bus.axes, -STROKE / 2))
        bus.wait_settled(5.0)
        emu.reset_stats()
        for k in range(sweeps):
            goal = STROKE / 2 if k % 2 == 0 else -STROKE / 2
            speeds = bus.sweep(dict.fromkeys(bus.axes, goal), dict.fromkeys(bus.axes, SPEED))
            these: list[StampedPositions] = []
            while True:
                poll = bus.poll_positions()
                middle = poll.middle_s
                for name, value in poll.positions.items():
                    truth = by_name[name].to_rad(round(motors[name].position_at(middle)))
                    error = abs(value - truth)
                    errors.append(error / TICK)
                    used.append(error / (TICK + speeds[name] * poll.window_s))
                these.append(poll)
                if poll.arrived:
                    break
            bus.wait_settled(5.0)
            rate_spans.append((len(these), these[-1].reply_s - these[0].request_s))
            polls.extend(these)
        reads = emu.stats.instructions["SYNC_READ"]
    count = sum(n for n, _ in rate_spans)
    span = sum(s for _, s in rate_spans)
    windows = sorted(p.window_s for p in polls)
    shortest = poll_seconds(len(AXES), baud)
    return {
        "polls": count,
        "rate": count / span,
        "rate_min": 1.0 / shortest,
        "efficiency": (count / span) * shortest,
        "window_ms": statistics.median(windows) * 1e3,
        "window_p95_ms": windows[int(0.95 * (len(windows) - 1))] * 1e3,
        "window_min_ms": shortest * 1e3,
        "bytes": poll_bytes(len(AXES)),
        "step_mrad": SPEED * span / count * 1e3,
        "retries": reads - count,
        "error_ticks": max(errors),
        "bound_used": max(used),
    }


def measure_apart(baud: int, sweeps: int) -> dict[str, float]:
    """As `measure`, with the emulator in a process of its own (``python -m
    sim.dynamixel.emulator``): the host does not share its interpreter with the motors.
    Rate and windows only (the motors' trajectory is not visible from here)."""
    command = [sys.executable, "-m", "sim.dynamixel.emulator", "--ids", "1-4"]
    server = subprocess.Popen(
        [*command, "--baud", str(baud)], stdout=subprocess.PIPE, text=True, cwd=ROOT
    )
    try:
        assert server.stdout is not None
        banner = server.stdout.readline()
        path = banner.split(" on ")[1].split(" at ")[0]
        polls: list[StampedPositions] = []
        span = 0.0
        with DynamixelBus(path, AXES, baud=baud, latency_ms=4.0) as bus:
            bus.move_to(dict.fromkeys(bus.axes, -STROKE / 2))
            bus.wait_settled(5.0)
            for k in range(sweeps):
                goal = STROKE / 2 if k % 2 == 0 else -STROKE / 2
                bus.sweep(dict.fromkeys(bus.axes, goal), dict.fromkeys(bus.axes, SPEED))
                these = [bus.poll_positions()]
                while not these[-1].arrived:
                    these.append(bus.poll_positions())
                bus.wait_settled(5.0)
                span += these[-1].reply_s - these[0].request_s
                polls.extend(these)
    finally:
        server.terminate()
        server.wait(10)
    windows = sorted(p.window_s for p in polls)
    return {
        "apart_rate": len(polls) / span,
        "apart_window_ms": statistics.median(windows) * 1e3,
        "apart_window_p95_ms": windows[int(0.95 * (len(windows) - 1))] * 1e3,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sweeps", type=int, default=4, help="sweeps per rate (there and back)")
    args = ap.parse_args()
    rows = {
        baud: measure(baud, args.sweeps) | measure_apart(baud, args.sweeps)
        for baud in (57_600, 1_000_000)
    }
    print(f"machine: {describe()}")
    print(
        f"4 axes, {args.sweeps} sweeps of {STROKE} rad at {SPEED} rad/s per rate, emulator "
        "with wire time and 500 µs return delay, host on time.monotonic\n"
    )
    lines = [
        ("polls during the sweeps", "polls", ".0f"),
        ("polls per second, measured", "rate", ".1f"),
        ("polls per second, theoretical (1 / shortest poll)", "rate_min", ".1f"),
        ("measured / theoretical", "efficiency", ".2f"),
        ("bytes on the line per poll", "bytes", ".0f"),
        ("poll window (reply − request), median, ms", "window_ms", ".2f"),
        ("poll window, 95th percentile, ms", "window_p95_ms", ".2f"),
        ("shortest poll (bytes × 10 / baud + return delays), ms", "window_min_ms", ".2f"),
        ("angle between polls at 1 rad/s, mrad", "step_mrad", ".2f"),
        ("polls retried (a reply missed its timeout)", "retries", ".0f"),
        ("largest error vs the emulator's trajectory, ticks", "error_ticks", ".2f"),
        ("largest error / (1 tick + v · window)", "bound_used", ".2f"),
        ("emulator in its own process: polls per second", "apart_rate", ".1f"),
        ("emulator in its own process: poll window, median, ms", "apart_window_ms", ".2f"),
        ("emulator in its own process: poll window, 95th pct, ms", "apart_window_p95_ms", ".2f"),
    ]
    two_rate_table(rows, lines)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Polling the bus during a sweep")
