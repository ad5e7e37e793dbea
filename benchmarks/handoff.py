"""The SDK and an in-process emulator sharing one interpreter: how long a raw 4-motor
SYNC_READ takes against its reply budget, with the interpreter's default switch interval
and with the one `sim.peers.responsive` sets while a server runs.

The ROBOTIS SDK polls its port in a tight loop while it waits; the emulator serves from
another thread of the same process, so every hand-off of the GIL waits for the switch
interval. For each interval: ``--repeat`` SYNC_READs of Present Position from 4 motors
(no wire time, the SDK's LATENCY_TIMER 16: a 44 ms budget), with ``--load`` busy
processes beside them; prints the median, p99 and worst time and the timeouts.
Run: .venv/bin/python benchmarks/handoff.py [--load 3] [--repeat 300]
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
import dynamixel_sdk as sdk
from _machine import describe
from dynamixel_sdk import COMM_SUCCESS, GroupSyncRead, port_handler

from sim.peers import responsive
from sim.peers.dynamixel.emulator import DxlEmulator

IDS = (1, 2, 3, 4)
PRESENT, SIZE = 132, 4
#: The interpreter's own default switch interval (s).
DEFAULT_SWITCH_INTERVAL_S = 0.005


def spin() -> None:
    while True:
        pass


def polls(switch_interval_s: float, repeat: int) -> tuple[list[float], int, float]:
    """Times (s) of ``repeat`` SYNC_READs, the timeouts among them, and the SDK's budget
    (ms), with the switch interval held at ``switch_interval_s`` while the emulator runs."""
    packets = sdk.PacketHandler(2.0)
    times: list[float] = []
    failed = 0
    with DxlEmulator(ids=IDS, wire_time=False, return_delay=False) as emu:
        sys.setswitchinterval(switch_interval_s)  # over what the emulator's start set
        port = sdk.PortHandler(emu.path)
        port.openPort()
        port.setBaudRate(emu.baud)
        reader = GroupSyncRead(port, packets, PRESENT, SIZE)
        for motor_id in IDS:
            reader.addParam(motor_id)
        for _ in range(repeat):
            started = time.perf_counter()
            failed += reader.txRxPacket() != COMM_SUCCESS
            times.append(time.perf_counter() - started)
        budget_ms = port.packet_timeout
        port.closePort()
    return times, failed, budget_ms


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--load", type=int, default=0, help="busy processes beside the test")
    parser.add_argument("--repeat", type=int, default=300)
    args = parser.parse_args()
    print(describe())
    port_handler.LATENCY_TIMER = 16  # the SDK's default
    hogs = [multiprocessing.Process(target=spin, daemon=True) for _ in range(args.load)]
    for hog in hogs:
        hog.start()
    try:
        print(
            f"\n4-motor SYNC_READ against the in-process emulator, {args.load} busy "
            f"processes, {args.repeat} reads each\n"
        )
        print("| switch interval | median ms | p99 ms | worst ms | budget ms | timeouts |")
        print("|---|---:|---:|---:|---:|---:|")
        for interval in (DEFAULT_SWITCH_INTERVAL_S, responsive.SERVING_SWITCH_INTERVAL_S):
            times, failed, budget = polls(interval, args.repeat)
            ms = sorted(1000 * t for t in times)
            p99 = ms[min(len(ms) - 1, int(0.99 * len(ms)))]
            print(
                f"| {1000 * interval:g} ms | {statistics.median(ms):.2f} | {p99:.1f} | "
                f"{ms[-1]:.1f} | {budget:.1f} | {failed} |",
                flush=True,
            )
    finally:
        for hog in hogs:
            hog.terminate()


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The SDK and an in-process emulator: GIL hand-offs")
