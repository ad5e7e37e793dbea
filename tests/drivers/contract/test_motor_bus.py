"""The `drivers.base.MotorBus` contract, rule by rule, on every motor backend."""

from __future__ import annotations

import math

import pytest

from drivers.errors import (
    CommError,
    DeviceClosed,
    DriverError,
    LimitError,
    MotionTimeout,
    MotorFault,
    TorqueOff,
)
from tests.drivers.contract.conftest import MOTOR_FAULTS, MotorHarness

FAULTS = {"motor_fault": MotorFault, "comm_error": CommError}


def test_close_is_idempotent_and_open_twice_is_harmless(motors: MotorHarness) -> None:
    bus = motors.make(None)
    bus.close()  # never opened
    with bus:
        bus.open()  # already open: nothing happens
        assert bus.is_open
    assert not bus.is_open
    bus.close()
    bus.close()


@pytest.mark.parametrize(
    "call",
    ["move_to", "wait_settled", "positions", "stop", "torque", "health", "recover"],
)
def test_every_call_on_a_closed_bus_raises_device_closed(motors: MotorHarness, call: str) -> None:
    bus = motors.make(None)
    args = {
        "move_to": (motors.target,),
        "wait_settled": (1.0,),
        "torque": (True,),
        "recover": (motors.faulted_axis,),
    }.get(call, ())
    for _ in (0, 1):  # before it was ever opened, and after it was closed
        with pytest.raises(DeviceClosed):
            getattr(bus, call)(*args)
        with bus:
            pass


def test_limits_are_checked_before_anything_is_sent(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        before = motors.observe()
        limits = bus.limits()
        axis = next(iter(limits))
        lo, hi = limits[axis]
        others = {a: v for a, v in motors.target.items() if a != axis}
        for bad in (hi + 1e-3, lo - 1e-3, math.nan, math.inf):
            with pytest.raises(LimitError, match=axis):
                bus.move_to({**others, axis: bad})
        with pytest.raises(DriverError, match="unknown axis"):
            bus.move_to({"no_such_axis": 0.0})
        motors.sync()
        motors.advance(10.0)
        assert motors.observe() == before  # the valid axes of a refused command stayed


def test_a_move_ends_at_the_goal_and_positions_are_read_back(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        bus.move_to(motors.target)
        motors.sync()
        motors.advance(30.0)
        bus.wait_settled(5.0)
        read = bus.positions()
        assert set(read) == set(bus.axes)
        for axis, goal in motors.target.items():
            assert read[axis] == pytest.approx(goal, abs=3e-3)  # within the tolerance
            assert read[axis] == motors.observe()[axis]  # read back, not the goal


def test_wait_settled_does_not_wait_the_settle_dwell(motors: MotorHarness) -> None:
    """The rig's settle dwell is the caller's (`gonio.acquire.measure`): once the motion
    has ended, waiting takes no virtual time on any backend."""
    bus = motors.make(None)
    with bus:
        bus.move_to(motors.target)
        motors.sync()
        motors.advance(30.0)  # far past the end of the move
        t = motors.clock.now()
        bus.wait_settled(5.0)
        assert motors.clock.now() == t


def test_torque_off_refuses_moves_and_sends_nothing(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        before = motors.observe()
        bus.torque(False)
        with pytest.raises(TorqueOff):
            bus.move_to(motors.target)
        motors.sync()
        motors.advance(10.0)
        bus.torque(True)
        motors.advance(10.0)
        assert motors.observe() == pytest.approx(before, abs=1e-9)  # no stale goal chased
        bus.move_to(motors.target)  # with torque on again it moves


@pytest.mark.parametrize("fault", MOTOR_FAULTS)
def test_a_fault_mid_move_holds_every_answering_axis_before_it_propagates(
    motors: MotorHarness, fault: str
) -> None:
    """The fault is caught inside the ``with`` block: the healthy axes must already be
    holding, short of their goals, not running on until the block is left."""
    bus = motors.make(fault)
    with bus:
        bus.move_to(motors.target)
        motors.arm()
        with pytest.raises(FAULTS[fault]) as info:
            bus.wait_settled(5.0)
        if fault == "motor_fault":
            assert isinstance(info.value, MotorFault)
            assert info.value.axis == motors.faulted_axis
            assert "overload" in info.value.flags
        motors.sync()
        held = motors.observe()
        motors.advance(30.0)  # long enough to have reached every goal
        after = motors.observe()
        for axis, goal in motors.target.items():
            if axis == motors.faulted_axis and fault == "motor_fault":
                continue
            assert after[axis] == pytest.approx(held[axis], abs=1e-9), axis
            assert abs(after[axis] - goal) > 0.05, axis  # stopped well short of the goal
        bus.stop()  # after a fault, stop holds again and never raises MotorFault


def test_a_timeout_holds_every_axis(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        bus.move_to(motors.target)
        motors.arm()
        with pytest.raises(MotionTimeout):
            bus.wait_settled(0.05)
        motors.sync()
        held = motors.observe()
        motors.advance(30.0)
        assert motors.observe() == pytest.approx(held, abs=1e-9)


def test_stop_holds_where_the_axes_are(motors: MotorHarness) -> None:
    bus = motors.make(None)
    with bus:
        bus.move_to(motors.target)
        motors.arm()
        bus.stop()
        motors.sync()
        held = motors.observe()
        motors.advance(30.0)
        assert motors.observe() == pytest.approx(held, abs=1e-9)
        health = bus.health()
        assert set(health) == set(bus.axes)
        assert all(h.ok for h in health.values())


def test_recover_reboots_only_the_faulted_motor_back_into_service(motors: MotorHarness) -> None:
    """After a hardware error mid-move: the motor rebooted, its error cleared, nothing
    moved by the recovery (it says where it held and reads the same), and it moves to a
    goal again; an unknown axis sends nothing."""
    bus = motors.make("motor_fault")
    with bus:
        bus.move_to(motors.target)
        motors.arm()
        with pytest.raises(MotorFault):
            bus.wait_settled(5.0)
        with pytest.raises(DriverError):
            bus.recover("no_such_axis")
        motors.sync()
        held = motors.observe()
        assert not bus.health()[motors.faulted_axis].ok  # latched until the reboot
        recovered = bus.recover(motors.faulted_axis)
        assert recovered.axis == motors.faulted_axis
        assert recovered.position_rad == pytest.approx(recovered.held_rad, abs=1e-9)
        motors.sync()
        motors.advance(30.0)
        assert motors.observe() == pytest.approx(held, abs=1e-9)  # every axis held
        assert all(h.ok for h in bus.health().values())
        bus.move_to(motors.target)  # torque on, configured: it moves again
        motors.sync()
        motors.advance(30.0)
        bus.wait_settled(5.0)
        assert bus.positions() == pytest.approx(motors.target, abs=2e-3)
