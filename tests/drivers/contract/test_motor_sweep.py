"""The sweep rules of the `drivers.base.MotorBus` contract (measuring while moving), on
every motor backend: a sweep at a chosen velocity, positions polled while it moves and
stamped at request and reply, its limits checked before anything moves, a fault met
while polling holding every axis."""

from __future__ import annotations

import itertools
import math

import pytest

from drivers.base import MotorBus
from drivers.errors import CommError, DeviceClosed, DriverError, LimitError, MotorFault, TorqueOff
from drivers.values import StampedPositions
from tests.drivers.contract.conftest import MOTOR_FAULTS, MotorHarness

FAULTS = {"motor_fault": MotorFault, "comm_error": CommError}
#: One encoder tick of a motor without gearing (rad): the finest step any backend reads.
TICK = 2 * math.pi / 4096
#: A sweep runs at this fraction of each axis's configured velocity.
SLOW = 0.25


def _sweep_and_poll(
    bus: MotorBus, motors: MotorHarness, target: dict[str, float], fraction: float = SLOW
) -> tuple[dict[str, float], dict[str, float], list[StampedPositions]]:
    """Start a sweep to ``target`` at ``fraction`` of the configured velocities and poll
    until it has arrived, letting about 1/25 of its cruise pass between polls; check each
    poll against where the motors really are. (start, commanded velocities, polls)."""
    start = bus.positions()
    top = bus.velocity_limits()
    commanded = bus.sweep(target, {a: fraction * top[a] for a in target})
    longest = max(abs(target[a] - start[a]) / commanded[a] for a in target)
    step = longest / 25
    polls: list[StampedPositions] = []
    for _ in range(200):
        motors.advance(step)
        poll = bus.poll_positions()
        truth = motors.observe()
        for axis, value in poll.positions.items():
            # Sampled within [request, reply]: at most v·(reply − request) from where the
            # motor is at the reply, plus the encoder's tick.
            bound = TICK + commanded.get(axis, 0.0) * poll.window_s + 1e-9
            assert abs(value - truth[axis]) <= bound, (axis, value, truth[axis])
        polls.append(poll)
        if poll.arrived:
            break
    assert polls[-1].arrived, "the sweep never arrived"
    return start, commanded, polls


def _cruise_speed(
    polls: list[StampedPositions], axis: str, start: float, goal: float
) -> tuple[float, float]:
    """(speed rad/s, its resolution rad/s) between the first and last polls that find
    ``axis`` in the middle half of its path (at cruise velocity there)."""
    inside = [p for p in polls if 0.25 <= (p.positions[axis] - start) / (goal - start) <= 0.75]
    assert len(inside) >= 3, f"{axis}: too few polls mid-path ({len(inside)})"
    first, last = inside[0], inside[-1]
    dt = last.middle_s - first.middle_s
    resolution = 2 * TICK / dt + (first.window_s + last.window_s) / dt
    return abs(last.positions[axis] - first.positions[axis]) / dt, resolution


def test_polls_during_a_sweep_walk_along_its_path(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        start, commanded, polls = _sweep_and_poll(bus, motors, motors.target)
        for axis, goal in motors.target.items():
            top = bus.velocity_limits()[axis]
            # the velocity actually commanded: the one asked, to the device's step
            assert commanded[axis] == pytest.approx(SLOW * top, rel=0.03)
            path = [p.positions[axis] for p in polls]
            sign = math.copysign(1.0, goal - start[axis])
            steps = [sign * (b - a) for a, b in zip([start[axis], *path], path, strict=False)]
            assert min(steps) >= -TICK, f"{axis} went back along its path"
            between = {v for v in path if abs(v - start[axis]) > TICK and abs(v - goal) > TICK}
            assert len(between) >= 5, f"{axis}: polls saw no motion"
            speed, resolution = _cruise_speed(polls, axis, start[axis], goal)
            assert speed == pytest.approx(commanded[axis], abs=resolution + 1e-9), axis
        for earlier, later in itertools.pairwise(polls):
            assert earlier.request_s <= earlier.reply_s <= later.request_s
            assert later.request_s > earlier.request_s
        bus.wait_settled(5.0)
        here = bus.positions()
        for axis, goal in motors.target.items():
            assert here[axis] == pytest.approx(goal, abs=3e-3)


def test_a_poll_at_rest_reads_the_positions(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        poll = bus.poll_positions()
        assert poll.request_s <= poll.reply_s
        assert poll.arrived
        assert set(poll.positions) == set(bus.axes)
        assert poll.positions == pytest.approx(bus.positions(), abs=1e-12)
        assert poll.positions == pytest.approx(motors.observe(), abs=1e-12)


def test_a_sweeps_profile_lasts_for_that_move_only(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        start, _, _ = _sweep_and_poll(bus, motors, motors.target)
        bus.wait_settled(5.0)
        back = {a: start[a] for a in motors.target}
        bus.move_to(back)  # the configured profile again: four times faster
        here = motors.target
        longest = max(abs(back[a] - here[a]) / bus.velocity_limits()[a] for a in back)
        polls = []
        for _ in range(200):
            motors.advance(longest / 25)
            polls.append(bus.poll_positions())
            if polls[-1].arrived:
                break
        for axis, goal in back.items():
            speed, resolution = _cruise_speed(polls, axis, here[axis], goal)
            top = bus.velocity_limits()[axis]
            # not the sweep's velocity any more (mid-path may still be accelerating)
            assert 2 * SLOW * top < speed <= top * 1.03 + resolution, axis


def test_a_sweep_is_refused_before_anything_moves(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        before = motors.observe()
        top = bus.velocity_limits()
        slow = {a: SLOW * top[a] for a in motors.target}
        axis = next(iter(motors.target))
        lo, hi = bus.limits()[axis]
        for bad in (hi + 1e-3, lo - 1e-3, math.nan):
            with pytest.raises(LimitError, match=axis):
                bus.sweep({**motors.target, axis: bad}, slow)
        for rate in (0.0, -1.0, math.nan, math.inf, 1.01 * top[axis]):
            with pytest.raises(LimitError, match=axis):
                bus.sweep(motors.target, {**slow, axis: rate})
        for rate in (0.0, -1.0, math.nan, math.inf, 1e6):  # above any configured acceleration
            with pytest.raises(LimitError, match=axis):
                bus.sweep(motors.target, slow, {axis: rate})
        with pytest.raises(LimitError, match=axis):
            bus.sweep(motors.target, {a: v for a, v in slow.items() if a != axis})
        with pytest.raises(DriverError, match="unknown axis"):
            bus.sweep({**motors.target, "no_such_axis": 0.0}, {**slow, "no_such_axis": 0.1})
        with pytest.raises(DriverError, match="no target"):
            bus.sweep({axis: motors.target[axis]}, slow)
        bus.torque(False)
        with pytest.raises(TorqueOff):
            bus.sweep(motors.target, slow)
        bus.torque(True)
        motors.sync()
        motors.advance(100.0)
        assert motors.observe() == pytest.approx(before, abs=1e-9)


def test_sweep_and_poll_on_a_closed_bus_raise_device_closed(motors: MotorHarness) -> None:
    bus = motors.make(None)
    for _ in (0, 1):  # before it was ever opened, and after it was closed
        with pytest.raises(DeviceClosed):
            bus.sweep(motors.target, dict.fromkeys(motors.target, 0.1))
        with pytest.raises(DeviceClosed):
            bus.poll_positions()
        with bus:
            pass


@pytest.mark.parametrize("fault", MOTOR_FAULTS)
def test_a_fault_met_while_polling_a_sweep_holds_every_axis(
    motors: MotorHarness, fault: str
) -> None:
    """Caught inside the ``with`` block: the healthy axes already hold, short of goal."""
    bus = motors.make(fault)
    with bus:
        start = bus.positions()
        top = bus.velocity_limits()
        commanded = bus.sweep(motors.target, {a: SLOW * top[a] for a in motors.target})
        step = max(abs(motors.target[a] - start[a]) / commanded[a] for a in motors.target) / 25
        motors.arm()

        def poll_until_it_fails() -> None:
            for _ in range(100):
                bus.poll_positions()
                motors.advance(step)

        with pytest.raises(FAULTS[fault]) as info:
            poll_until_it_fails()
        if fault == "motor_fault":
            assert isinstance(info.value, MotorFault)
            assert info.value.axis == motors.faulted_axis
        motors.sync()
        held = motors.observe()
        motors.advance(1000.0)  # long enough to have reached every goal at sweep speed
        after = motors.observe()
        for axis, goal in motors.target.items():
            if axis == motors.faulted_axis and fault == "motor_fault":
                continue
            assert after[axis] == pytest.approx(held[axis], abs=1e-9), axis
            assert abs(after[axis] - goal) > 0.05, axis
        bus.stop()
