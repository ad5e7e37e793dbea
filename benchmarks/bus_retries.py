"""The Dynamixel bus's retries against lost status packets, measured on the emulator.

4 axes on the byte-level emulator over a real pty (wire time and the motors' 500 µs
return delay on; served from a process of its own, so the SDK's busy wait does not
starve it of the GIL, scheduled before other work where the system allows, as hardware
is never descheduled), driven by the real `DynamixelLink` / `DynamixelBus` with their
default retries (3 extra attempts) and the reply timeouts of an adapter at the FTDI
default latency timer, 16 ms (``latency_ms`` 16, the link's own choice when sysfs does
not say; the emulator adds no adapter latency itself; on a loaded shared machine
shorter timeouts time out with no loss at all, which the 0 % row would show). The emulator loses
each status packet at random with a probability of 0 %, 0.1 %, 1 % and 5 %
(`DxlEmulator.inject_rate`, `Fault.NO_REPLY`).

For each rate: the share of SYNC_READ polls of Present Position that needed a retry (a
lost status: the link waits its timeout, drains the line and asks again) and that
failed after all 4 attempts (`CommError`, which stops a run resumable), each beside
what independent losses predict (a poll needs all 4 statuses: it fails an attempt with
probability q = 1 − (1 − p)⁴, and for good with q⁴; with 5 retries it would with q⁶);
the mean and 99th-percentile time per poll; and the mean time per sample on the bus
(one stop-and-go step with no motion: the SYNC_WRITE of goals and the polls until
settled). Prints a markdown table per baud rate.
Run: .venv/bin/python benchmarks/bus_retries.py [--polls N] [--steps N]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import statistics
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from multiprocessing.connection import Connection
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe
from bus import AXES  # the four axes benchmarks/bus.py times

from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError
from sim.peers.dynamixel.emulator import DxlEmulator, Fault

IDS = [a.motor_id for a in AXES]
LOSS_RATES = (0.0, 0.001, 0.01, 0.05)
#: The link's and the bus's default number of extra attempts.
RETRIES = 3
#: The larger number of extra attempts the table compares with.
MORE_RETRIES = 5
#: The adapter latency (ms) whose reply timeouts the link uses (`--adapter-ms`).
ADAPTER_MS = 16.0
#: How the emulator's processes were scheduled (`prioritize`).
PRIORITY: set[str] = set()


def prioritize() -> str:
    """Run this process (the emulator: hardware is never descheduled) before the others:
    real-time FIFO scheduling where allowed, else a lower niceness, else as it is. The
    emulator sleeps between packets, so it takes no more CPU than it did."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
        return "real-time (SCHED_FIFO)"
    except (OSError, AttributeError):
        pass
    try:
        os.nice(-10)
        return "niceness lowered by 10"
    except OSError:
        return "normal priority (no right to raise it)"


class Emulator:
    """The emulator in a child process: its pty path, and its loss rate set by message."""

    def __init__(self, conn: Connection, priority: str, path: str) -> None:
        self._conn = conn
        self.priority = priority
        self.path = path

    def lose(self, rate: float, seed: int = 1) -> None:
        """Lose each status packet with probability ``rate`` from now on."""
        self._conn.send((rate, seed))
        self._conn.recv()


def _serve(conn: Connection, baud: int) -> None:
    priority = prioritize()
    with DxlEmulator(ids=IDS, baud=baud) as emu:
        conn.send((priority, emu.path))
        while (message := conn.recv()) is not None:
            rate, seed = message
            emu.inject_rate(Fault.NO_REPLY, rate, seed=seed)
            conn.send(True)


@contextmanager
def emulator(baud: int) -> Iterator[Emulator]:
    ours, theirs = multiprocessing.Pipe()
    child = multiprocessing.get_context("fork").Process(target=_serve, args=(theirs, baud))
    child.start()
    try:
        yield Emulator(ours, *ours.recv())
    finally:
        ours.send(None)
        child.join(5.0)
        if child.is_alive():
            child.kill()


class CountingLink(DynamixelLink):
    """The link, counting its failed attempts (each is followed by one drain)."""

    failed_attempts = 0

    def _drain(self) -> None:
        self.failed_attempts += 1
        super()._drain()


def polls(emu: Emulator, baud: int, rate: float, count: int, adapter_ms: float) -> dict[str, float]:
    """``count`` SYNC_READs of Present Position losing each status at ``rate``."""
    retried = failed = 0
    times: list[float] = []
    with CountingLink(emu.path, baud, retries=RETRIES, latency_ms=adapter_ms) as link:
        emu.lose(rate)
        for _ in range(count):
            before = link.failed_attempts
            t = time.perf_counter()
            try:
                link.sync_read(IDS, "present_position", "present_position")
            except CommError:
                failed += 1
            times.append(time.perf_counter() - t)
            retried += link.failed_attempts > before
        emu.lose(0.0)
    times.sort()
    return {
        "retried": retried / count,
        "failed": failed / count,
        "failed_n": failed,
        "mean_ms": 1e3 * statistics.fmean(times),
        "p99_ms": 1e3 * times[min(len(times) - 1, int(0.99 * len(times)))],
    }


def steps(emu: Emulator, baud: int, rate: float, count: int, adapter_ms: float) -> dict[str, float]:
    """``count`` hold steps (move to where the axes are, wait until settled) on the bus
    (opened before the loss starts, as a run opens it once) losing each status at
    ``rate``; a step that raised counts as failed (the bus has held the axes)."""
    failed = 0
    times: list[float] = []
    with DynamixelBus(emu.path, AXES, baud=baud, retries=RETRIES, latency_ms=adapter_ms) as bus:
        here = bus.positions()
        emu.lose(rate, seed=2)
        for _ in range(count):
            t = time.perf_counter()
            try:
                bus.move_to(here)
                bus.wait_settled(2.0)
            except DriverError:
                failed += 1
            times.append(time.perf_counter() - t)
        emu.lose(0.0)  # the bus holds and closes loss-free
    return {"step_ms": 1e3 * statistics.fmean(times), "step_failed": failed}


def measure(baud: int, n_polls: int, n_steps: int, adapter_ms: float) -> list[dict[str, float]]:
    rows = []
    for rate in LOSS_RATES:
        with emulator(baud) as emu:
            PRIORITY.add(emu.priority)
            row = {"rate": rate, **polls(emu, baud, rate, n_polls, adapter_ms)}
            row |= steps(emu, baud, rate, n_steps, adapter_ms)
        q = 1.0 - (1.0 - rate) ** len(IDS)
        row |= {
            "retried_expected": q,
            "failed_expected": q ** (RETRIES + 1),
            "failed_expected_more": q ** (MORE_RETRIES + 1),
        }
        rows.append(row)
    return rows


def table(baud: int, rows: list[dict[str, float]], n_polls: int, n_steps: int) -> None:
    print(
        f"\n**{baud:,} baud** ({n_polls} polls and {n_steps} steps per loss rate)\n".replace(
            ",", " "
        )
    )
    print(
        "| status packets lost | polls retried (expected) | polls failed after "
        f"{RETRIES + 1} attempts (expected; with {MORE_RETRIES} retries) | time per poll, "
        "mean / p99 (ms) | time per sample on the bus (ms) | samples failed |"
    )
    print("| ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print(
            f"| {100 * r['rate']:g} % | {100 * r['retried']:.2f} % "
            f"({100 * r['retried_expected']:.2f} %) | {int(r['failed_n'])} = "
            f"{100 * r['failed']:.3f} % ({100 * r['failed_expected']:.2g} %; "
            f"{100 * r['failed_expected_more']:.2g} %) | "
            f"{r['mean_ms']:.2f} / {r['p99_ms']:.1f} | {r['step_ms']:.2f} | "
            f"{int(r['step_failed'])} |"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--polls", type=int, default=5000, help="polls per loss rate and baud")
    ap.add_argument(
        "--adapter-ms",
        type=float,
        default=ADAPTER_MS,
        help="the adapter latency (ms) of the timeouts",
    )
    ap.add_argument("--steps", type=int, default=300, help="hold steps per loss rate and baud")
    ap.add_argument("--bauds", type=int, nargs="+", default=[57_600, 1_000_000])
    args = ap.parse_args()
    print(f"machine: {describe()}")
    print(
        f"4 axes, emulator with wire time and 500 µs return delay; retries {RETRIES}; "
        f"reply timeouts of a {args.adapter_ms:g} ms adapter"
    )
    print(
        "'retried': the poll lost a status and asked again; 'failed': all attempts lost one "
        "(CommError: a run stops, resumable); expected: independent losses"
    )
    for baud in args.bauds:
        rows = measure(baud, args.polls, args.steps, args.adapter_ms)
        table(baud, rows, args.polls, args.steps)
    print(f"\nThe emulator's process ran at {', '.join(sorted(PRIORITY))}.")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The Dynamixel bus: retries against lost packets")
