"""Streaming a trajectory on the Dynamixel bus: the set-point rate and the tracking error
on the rehearsal path, against the bus's theoretical budget.

For 4 axes at 57 600 and 1 000 000 baud, `DynamixelBus.follow` drives the byte-level
emulator over a real pty in real time (bytes timed on the wire, the motors' default 500
µs return delay, the host on `time.monotonic`, up to 9 attempts per transaction). Each
trajectory moves the four axes together along a curve (a cosine time law between two
poses 1.2 rad apart per axis, the first axis going out 0.4 rad and back instead, so that
it turns), at half the configured velocity (4 rad/s) and acceleration (40 rad/s²),
sampled at the bus's set-point period (`drivers.dynamixel.wire.setpoint_period`: one
SYNC_WRITE of 12 bytes per motor and one SYNC_READ poll per period, their wire time at
most half of it); the runs go there and back. The theoretical budget is the wire time of
one period (`setpoint_seconds`: the SYNC_WRITE's bytes and the poll's, × 10 bits / baud,
plus the return delays). The set-point rate achieved is (K − 1) / (last send − first
send); a send's lateness is its time after it was due; the tracking error is what
`follow` reports (the largest distance of a poll from the path at the poll's middle),
and the motors' own distance from the path is read from the emulator's trajectories at
the same instants. Prints a markdown table.
Run: .venv/bin/python benchmarks/trajectory_bus.py [--runs N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe
from bus import AXES, two_rate_table  # the four axes benchmarks/bus.py times

from drivers.dynamixel import setpoint_period, setpoint_seconds, sync_write_bytes
from drivers.dynamixel.bus import DynamixelBus
from drivers.trajectory import Trajectory
from drivers.values import StampedPositions
from sim.peers.dynamixel.emulator import DxlEmulator

SHARE = 0.5  # of the configured velocity and acceleration
STROKE = 1.2  # rad per axis
TURN = 0.4  # rad, the first axis out and back
TICK = 2 * math.pi / 4096
#: Extra attempts per transaction: a shared machine may starve the emulator's thread for
#: longer than the driver's default three.
RETRIES = 8


def curve(start: np.ndarray, end: np.ndarray, period: float) -> Trajectory:
    """Every axis from ``start`` to ``end`` on a cosine time law, the first one out by
    `TURN` and back instead, as fast as `SHARE` of the configured rates allow."""
    tau = np.linspace(0.0, 1.0, 4001)
    s = 0.5 * (1.0 - np.cos(math.pi * tau))
    shape = start + np.outer(s, end - start)
    shape[:, 0] = start[0] - math.copysign(TURN, start[0]) * np.sin(math.pi * s)
    d1 = np.max(np.abs(np.gradient(shape, tau, axis=0)))
    d2 = np.max(np.abs(np.gradient(np.gradient(shape, tau, axis=0), tau, axis=0)))
    top_v = SHARE * AXES[0].profile_velocity_rad_s
    top_a = SHARE * AXES[0].profile_acceleration_rad_s2
    duration = max(d1 / top_v, math.sqrt(d2 / top_a))
    t = np.minimum(np.arange(math.ceil(duration / period) + 1) * period / duration, 1.0)
    goals = np.column_stack([np.interp(t, tau, shape[:, j]) for j in range(len(start))])
    return Trajectory(tuple(a.name for a in AXES), period, goals)


def measure(baud: int, runs: int) -> dict[str, float]:
    """One emulator and bus at ``baud``: ``runs`` trajectories there and back."""
    period = setpoint_period(len(AXES), baud)
    here = np.full(len(AXES), -STROKE / 2)
    rates, late, busy, tracking, truth, settle = [], [], [], [], [], []
    count = retries = 0
    seen: list[list[float]] = []  # the motors' own positions at the present run's polls
    with (
        DxlEmulator(ids=range(1, 5), baud=baud) as emu,
        DynamixelBus(emu.path, AXES, baud=baud, latency_ms=4.0, retries=RETRIES) as bus,
    ):
        pairs = [(a, emu.motors[a.motor_id]) for a in AXES]
        for _ in range(runs):
            trajectory = curve(here, -here, period)
            bus.move_to(dict(zip(trajectory.axes, trajectory.goals[0].tolist(), strict=True)))
            bus.wait_settled(10.0)
            seen.clear()

            def on_poll(poll: StampedPositions) -> None:
                # the motors' own position at the poll's middle, while the emulator still
                # remembers the trajectory it was on then
                seen.append([a.to_rad(round(m.position_at(poll.middle_s))) for a, m in pairs])

            reads = emu.stats.instructions["SYNC_READ"]
            followed = bus.follow(trajectory, on_poll)
            retries += emu.stats.instructions["SYNC_READ"] - reads - len(followed.polls)
            sent = np.asarray(followed.sent_s)
            count += len(sent)
            rates.append((len(sent) - 1) / (sent[-1] - sent[0]))
            late.extend(sent - (followed.started_s + np.arange(len(sent)) * period))
            busy.extend(p.reply_s - s for p, s in zip(followed.polls, sent, strict=True))
            tracking.append(followed.tracking_rad)
            middles = np.array([p.middle_s for p in followed.polls])
            path = trajectory.at(middles - followed.started_s)
            truth.append(float(np.max(np.abs(np.array(seen) - path))))
            settle.append(followed.ended_s - sent[-1] - period)
            here = -here
    budget = setpoint_seconds(len(AXES), baud)
    late_ms = np.asarray(late) * 1e3
    return {
        "setpoints": count,
        "period_ms": period * 1e3,
        "rate": statistics.median(rates),
        "rate_min": min(rates),
        "rate_scheduled": 1.0 / period,
        "rate_budget": 1.0 / budget,
        "budget_ms": budget * 1e3,
        "write_bytes": sync_write_bytes(len(AXES)),
        "busy_ms": statistics.median(busy) * 1e3,
        "busy_p95_ms": float(np.percentile(busy, 95)) * 1e3,
        "late_ms": float(np.median(late_ms)),
        "late_max_ms": float(np.max(late_ms)),
        "late_periods": int(np.sum(late_ms > period * 1e3)),
        "retries": retries,
        "tracking_mrad": max(tracking) * 1e3,
        "tracking_ticks": max(tracking) / TICK,
        "truth_mrad": max(truth) * 1e3,
        "settle_ms": statistics.median(settle) * 1e3,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=4, help="trajectories per rate (there and back)")
    args = ap.parse_args()
    rows = {baud: measure(baud, args.runs) for baud in (57_600, 1_000_000)}
    print(f"machine: {describe()}")
    print(
        f"4 axes, {args.runs} trajectories per rate at half the configured velocity and "
        "acceleration, emulator with wire time and 500 µs return delay, host on "
        "time.monotonic\n"
    )
    lines = [
        ("set-points sent", "setpoints", ".0f"),
        ("set-point period, ms", "period_ms", ".0f"),
        ("set-points per second, achieved (median run)", "rate", ".2f"),
        ("set-points per second, achieved (slowest run)", "rate_min", ".2f"),
        ("set-points per second, scheduled (1 / period)", "rate_scheduled", ".2f"),
        ("set-points per second, theoretical (1 / wire time of a period)", "rate_budget", ".1f"),
        ("wire time of a period (SYNC_WRITE + SYNC_READ + return delays), ms", "budget_ms", ".2f"),
        ("bytes of one set-point's SYNC_WRITE", "write_bytes", ".0f"),
        ("write + poll as measured (send to poll reply), median, ms", "busy_ms", ".2f"),
        ("write + poll as measured, 95th percentile, ms", "busy_p95_ms", ".2f"),
        ("a send's lateness after its due time, median, ms", "late_ms", ".2f"),
        ("a send's lateness, largest, ms", "late_max_ms", ".2f"),
        ("sends later than one period", "late_periods", ".0f"),
        ("polls retried (a reply missed its timeout)", "retries", ".0f"),
        ("tracking error reported by follow, largest, mrad", "tracking_mrad", ".2f"),
        ("tracking error reported by follow, largest, ticks", "tracking_ticks", ".1f"),
        ("motors' own distance from the path at the polls, largest, mrad", "truth_mrad", ".2f"),
        ("settling after the last set-point's period, median, ms", "settle_ms", ".1f"),
    ]
    two_rate_table(rows, lines)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Streaming a trajectory on the bus")
