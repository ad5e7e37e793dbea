"""The trajectory rules of the `drivers.base.MotorBus` contract (coordinated multi-axis
motion), on every motor backend: a trajectory followed within the backend's stated
tracking error, its polls stamped and ordered, its set-points sent on time, everything
checked before the first byte, a fault or an exception of ``on_poll`` mid-trajectory
holding every axis."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from drivers.base import MotorBus
from drivers.errors import (
    CommError,
    DeviceClosed,
    DriverError,
    LimitError,
    MotorFault,
    TorqueOff,
)
from drivers.trajectory import Trajectory
from drivers.values import StampedPositions
from tests.drivers.contract.conftest import MOTOR_FAULTS, MotorHarness

FAULTS = {"motor_fault": MotorFault, "comm_error": CommError}
#: A trajectory runs at this fraction of each axis's configured velocity and acceleration.
SHARE = 0.5


def _trajectory(
    bus: MotorBus,
    motors: MotorHarness,
    start: dict[str, float],
    end: dict[str, float],
    turn: bool = True,
) -> Trajectory:
    """A curve in joint space from ``start`` to ``end`` (every axis of ``end``), each
    axis on a cosine time law, as fast as `SHARE` of the slowest axis's velocity and
    acceleration allow; with ``turn`` the first axis goes out toward the middle of its
    limits and back instead."""
    axes = tuple(end)
    tau = np.linspace(0.0, 1.0, 2001)
    s = 0.5 * (1.0 - np.cos(math.pi * tau))
    a0 = np.array([start[a] for a in axes])
    a1 = np.array([end[a] for a in axes])
    if turn:
        a1[0] = a0[0]
    shape = a0 + np.outer(s, a1 - a0)
    if turn:
        middle = 0.5 * sum(bus.limits()[axes[0]])
        shape[:, 0] += 0.5 * (middle - a0[0]) * np.sin(math.pi * s)  # out and back
    d1 = np.max(np.abs(np.gradient(shape, tau, axis=0)), axis=0)
    d2 = np.max(np.abs(np.gradient(np.gradient(shape, tau, axis=0), tau, axis=0)), axis=0)
    top_v = np.array([bus.velocity_limits()[a] for a in axes])
    top_a = np.array([motors.accelerations[a] for a in axes])
    duration = max(np.max(d1 / (SHARE * top_v)), math.sqrt(np.max(d2 / (SHARE * top_a))))
    period = motors.period_s
    count = math.ceil(duration / period) + 1
    t = np.minimum(np.arange(count) * period / duration, 1.0)
    goals = np.column_stack([np.interp(t, tau, shape[:, j]) for j in range(len(axes))])
    return Trajectory(axes, period, goals)


def _at_start(bus: MotorBus, trajectory: Trajectory) -> None:
    bus.move_to(dict(zip(trajectory.axes, trajectory.goals[0].tolist(), strict=True)))
    bus.wait_settled(10.0)


def _mirrored(bus: MotorBus, motors: MotorHarness) -> dict[str, float]:
    """The harness's target mirrored through the middle of each axis's limits."""
    return {a: sum(bus.limits()[a]) - x for a, x in motors.target.items()}


def test_a_trajectory_is_followed_within_the_stated_tracking_error(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        trajectory = _trajectory(bus, motors, motors.target, _mirrored(bus, motors))
        _at_start(bus, trajectory)
        seen: list[StampedPositions] = []
        truth: list[tuple[float, list[float]]] = []

        def on_poll(poll: StampedPositions) -> None:
            seen.append(poll)
            here = motors.observe()  # the device's own state, now
            truth.append((motors.clock.now(), [here[a] for a in trajectory.axes]))

        followed = bus.follow(trajectory, on_poll)
        assert followed.polls == seen
        assert len(followed.polls) == len(followed.sent_s) == len(trajectory)
        assert followed.tracking_rad <= motors.tracking_bound
        # set-point k left when it was due, the polls stamped in order between the writes
        due = followed.started_s + np.arange(len(trajectory)) * trajectory.period_s
        assert np.asarray(followed.sent_s) == pytest.approx(due, abs=1e-6)
        for sent, poll in zip(followed.sent_s, followed.polls, strict=True):
            assert sent <= poll.request_s <= poll.reply_s
        for earlier, later in itertools.pairwise(followed.polls):
            assert earlier.reply_s <= later.request_s
        assert followed.ended_s >= followed.polls[-1].reply_s
        # the device itself was on the path while it was followed (not only the polls)
        times = np.array([t for t, _ in truth]) - followed.started_s
        observed = np.array([x for _, x in truth])
        assert np.max(np.abs(observed - trajectory.at(times))) <= motors.tracking_bound
        # the first axis turned back on the way, and every axis ended at the last set-point
        first = np.array([p.positions[trajectory.axes[0]] for p in followed.polls])
        planned = np.ptp(trajectory.goals[:, 0])
        assert planned > 0.05
        assert np.ptp(first) > 0.9 * planned - 2 * motors.tracking_bound  # polls sample it
        end = dict(zip(trajectory.axes, trajectory.goals[-1].tolist(), strict=True))
        assert bus.positions() == pytest.approx(end, abs=3e-3)
        assert motors.observe() == pytest.approx(end, abs=3e-3)


def test_the_next_move_runs_the_configured_profile_again(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        trajectory = _trajectory(bus, motors, motors.target, _mirrored(bus, motors))
        _at_start(bus, trajectory)
        bus.follow(trajectory)
        back = motors.target
        bus.move_to(back)
        motors.sync()
        here = dict(zip(trajectory.axes, trajectory.goals[-1].tolist(), strict=True))
        # at the configured velocity the longest axis needs about this long (plus ramps)
        cruise = max(abs(back[a] - here[a]) / bus.velocity_limits()[a] for a in back)
        motors.advance(
            1.5 * cruise + max(bus.velocity_limits()[a] / motors.accelerations[a] for a in back)
        )
        assert bus.poll_positions().arrived


def test_a_trajectory_is_refused_before_anything_is_sent(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        good = _trajectory(bus, motors, motors.target, _mirrored(bus, motors))
        _at_start(bus, good)
        motors.sync()
        before, sent = motors.observe(), motors.goals_sent()
        axis = good.axes[0]
        lo, hi = bus.limits()[axis]
        for bad in (hi + 1e-3, lo - 1e-3, math.nan):
            goals = good.goals.copy()
            goals[len(goals) // 2, 0] = bad
            with pytest.raises(LimitError, match=axis):
                bus.follow(Trajectory(good.axes, good.period_s, goals))
        # twice as fast: above the configured velocity or acceleration
        with pytest.raises(LimitError, match="configured"):
            bus.follow(Trajectory(good.axes, good.period_s / 4, good.goals))
        with pytest.raises(DriverError, match="unknown axis"):
            bus.follow(Trajectory(("no_such_axis",), good.period_s, good.goals[:, :1]))
        # not at rest at set-point 0
        elsewhere = Trajectory(good.axes, good.period_s, good.goals[::-1])
        with pytest.raises(DriverError, match="set-point 0"):
            bus.follow(elsewhere)
        bus.torque(False)
        with pytest.raises(TorqueOff):
            bus.follow(good)
        assert motors.goals_sent() == sent
        bus.torque(True)
        motors.sync()
        motors.advance(100.0)
        assert motors.observe() == pytest.approx(before, abs=1e-9)


def test_follow_on_a_closed_bus_raises_device_closed(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        trajectory = _trajectory(bus, motors, motors.target, _mirrored(bus, motors))
    for _ in (0, 1):  # after it was closed, and again
        with pytest.raises(DeviceClosed):
            bus.follow(trajectory)


def _held_short_of_the_end(
    motors: MotorHarness, trajectory: Trajectory, skip: str | None = None
) -> None:
    """Every axis (but ``skip``, a faulted one) holds where it is, short of the end."""
    motors.sync()
    held = motors.observe()
    motors.advance(1000.0)
    after = motors.observe()
    for axis, goal in zip(trajectory.axes, trajectory.goals[-1].tolist(), strict=True):
        if axis == skip:
            continue
        assert after[axis] == pytest.approx(held[axis], abs=1e-9), axis
        assert abs(after[axis] - goal) > 0.05, axis


@pytest.mark.parametrize("fault", MOTOR_FAULTS)
def test_a_fault_mid_trajectory_holds_every_axis(motors: MotorHarness, fault: str) -> None:
    """The trajectory is the bus's first motion (a simulated fault strikes half-way
    through it); the emulator's is injected at the poll half-way."""
    bus = motors.make(fault)
    with bus:
        trajectory = _trajectory(bus, motors, bus.positions(), motors.target, turn=False)
        polls: list[StampedPositions] = []

        def on_poll(poll: StampedPositions) -> None:
            polls.append(poll)
            if len(polls) == len(trajectory) // 2:
                motors.arm()

        with pytest.raises(FAULTS[fault]) as info:
            bus.follow(trajectory, on_poll)
        if fault == "motor_fault":
            assert isinstance(info.value, MotorFault)
            assert info.value.axis == motors.faulted_axis
        assert len(trajectory) // 3 < len(polls) < len(trajectory)
        skip = motors.faulted_axis if fault == "motor_fault" else None
        _held_short_of_the_end(motors, trajectory, skip)
        bus.stop()


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_on_poll_raising_holds_every_axis(motors: MotorHarness, error: type[BaseException]) -> None:
    bus = motors.make(None)
    with bus:
        trajectory = _trajectory(bus, motors, motors.target, _mirrored(bus, motors))
        _at_start(bus, trajectory)
        polls: list[StampedPositions] = []

        def on_poll(poll: StampedPositions) -> None:
            polls.append(poll)
            if len(polls) == len(trajectory) // 2:
                raise error("the caller's stream failed")

        with pytest.raises(error, match="stream failed"):
            bus.follow(trajectory, on_poll)
        assert len(polls) == len(trajectory) // 2
        _held_short_of_the_end(motors, trajectory)
