"""One sweep of a fly plan measured on the devices (docs/explanations/acquisition.md).

`run_sweep`: move to the sweep's start (at rest) and settle, start the detector's stream,
command the sweep (the swept axes at the plan's velocity, to the stop pose), then poll
the positions and read the stream in turn until the motion is over (on the simulated
backend both advance the one virtual clock), stop the stream. What comes back is raw
(`RawSweep`): the stamped polls, the velocities the bus commanded and the stamped
readings, stamped again with the stream's final clock offset (`drivers.stream.restamped`,
the latency the live stamps assumed). Merging them is `gonio.acquire.fly.merge`'s.

`run_path_sweep`: a path sweep (a trajectory every axis follows): move to its first
set-point (at rest) and settle, poll the positions there (the first window starts after
it), start the detector's stream, follow the trajectory
(`drivers.base.MotorBus.follow`: a write of every axis's set-point and a poll per
period), reading the stream after each poll, then stop the stream. Its `RawSweep` also
holds the trajectory's origin on the clock (set-point 0 due). `run_sweep` runs it for a
sweep with set-points.
"""

from __future__ import annotations

from drivers.devices import Devices
from drivers.stream import StreamReading, restamped, streaming
from drivers.trajectory import Trajectory
from drivers.values import StampedPositions
from gonio.acquire.fly.merge import RawSweep
from gonio.planner import Sweeps


def run_sweep(
    devices: Devices,
    axes: tuple[str, ...],
    sweeps: Sweeps,
    k: int,
    *,
    settle_s: float,
    timeout_s: float,
) -> RawSweep:
    """Measure sweep ``k`` of ``sweeps`` (see the module docstring). A driver error
    propagates with the stream stopped (the bus already held the axes)."""
    if int(sweeps.path_count[k]):
        return run_path_sweep(devices, axes, sweeps, k, settle_s=settle_s, timeout_s=timeout_s)
    bus, clock = devices.bus, devices.clock
    detector = streaming(devices.detector)
    start = dict(zip(axes, sweeps.start[k].tolist(), strict=True))
    stop = dict(zip(axes, sweeps.stop[k].tolist(), strict=True))
    moving = {a: abs(v) for a, v in zip(axes, sweeps.velocity[k].tolist(), strict=True) if v}
    started = _settled_at(devices, start, settle_s, timeout_s)
    polls: list[StampedPositions] = []
    readings: list[StreamReading] = []
    detector.start_stream(1.0 / sweeps.period_s, sweeps.integration_s)
    try:
        commanded = bus.sweep({a: stop[a] for a in moving}, moving)
        deadline = started + timeout_s
        while True:
            poll = bus.poll_positions()
            polls.append(poll)
            readings += detector.read_stream(0.0)
            if poll.arrived or poll.reply_s > deadline:
                break
    finally:
        readings += detector.stop_stream()
    bus.wait_settled(timeout_s)
    return RawSweep(polls, restamped(readings, None), started, clock.now(), velocities=commanded)


def run_path_sweep(
    devices: Devices,
    axes: tuple[str, ...],
    sweeps: Sweeps,
    k: int,
    *,
    settle_s: float,
    timeout_s: float,
) -> RawSweep:
    """Measure path sweep ``k`` of ``sweeps`` (the module docstring). A driver error
    propagates with the stream stopped (the bus already held the axes)."""
    bus, clock = devices.bus, devices.clock
    detector = streaming(devices.detector)
    trajectory = Trajectory(axes, sweeps.path_period_s, sweeps.set_points(k))
    start = dict(zip(axes, trajectory.goals[0].tolist(), strict=True))
    started = _settled_at(devices, start, settle_s, timeout_s)
    readings: list[StreamReading] = []

    def read(_: StampedPositions) -> None:
        readings.extend(detector.read_stream(0.0))

    at_rest = bus.poll_positions()  # where the first window starts: before it
    detector.start_stream(1.0 / sweeps.period_s, sweeps.integration_s)
    try:
        followed = bus.follow(trajectory, read)
    finally:
        readings += detector.stop_stream()
    polls = [at_rest, *followed.polls]
    return RawSweep(polls, restamped(readings, None), started, clock.now(), followed.started_s)


def _settled_at(devices: Devices, pose: dict[str, float], settle_s: float, timeout_s: float
                ) -> float:  # fmt: skip
    """Move to ``pose`` (rad), wait until settled and the rig's settle dwell; the clock's
    time then (s)."""
    devices.bus.move_to(pose)
    devices.bus.wait_settled(timeout_s)
    devices.clock.sleep(settle_s)
    return devices.clock.now()
