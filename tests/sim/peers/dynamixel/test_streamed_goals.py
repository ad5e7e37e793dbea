"""Streamed set-points on the emulated X series: Profile Acceleration, Profile Velocity
and Goal Position written together (addresses 108-119) every period while the motor
moves re-plan its profile from its present position and velocity, so a motor whose goal
keeps running ahead cruises without ever stopping, and a new profile velocity is
reached at the profile acceleration from the velocity it had."""

from __future__ import annotations

import itertools

import pytest

from drivers.dynamixel.control_table import item
from sim.clock import ManualClock
from sim.peers.dynamixel.motion import (
    TICKS_PER_S2_PER_ACCELERATION_UNIT,
    TICKS_PER_S_PER_VELOCITY_UNIT,
)
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import StatusError

PERIOD = 0.02  # s between set-points
ACCEL = 30  # Profile Acceleration register (≈ 6.3 rad/s² at the shaft)


def setpoint(motor: EmulatedMotor, acceleration: int, velocity: int, goal: int) -> None:
    """One set-point as `DynamixelBus.follow` writes it: one write of 108-119."""
    data = b"".join(
        item(name).encode(value)
        for name, value in (
            ("profile_acceleration", acceleration),
            ("profile_velocity", velocity),
            ("goal_position", goal),
        )
    )
    assert motor.write(item("profile_acceleration").address, data) == StatusError.NONE


@pytest.fixture
def motor(clock: ManualClock) -> EmulatedMotor:
    m = EmulatedMotor(1, clock=clock)
    assert m.write(item("torque_enable").address, b"\x01") == StatusError.NONE
    return m


def test_a_goal_running_ahead_keeps_the_motor_cruising(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    start = motor.get("present_position")
    speed = 40  # velocity register: ≈ 0.96 rad/s
    ticks_per_period = speed * TICKS_PER_S_PER_VELOCITY_UNIT * PERIOD
    velocities = []
    for k in range(100):
        # the goal 10 periods ahead of where the path is: far beyond the braking distance
        goal = start + round((k + 10) * ticks_per_period)
        setpoint(motor, ACCEL, speed, goal)
        for _ in range(4):
            clock.advance(PERIOD / 4)
            velocities.append(motor.get("present_velocity"))
    ramp = (
        round(
            speed
            * TICKS_PER_S_PER_VELOCITY_UNIT
            / (ACCEL * TICKS_PER_S2_PER_ACCELERATION_UNIT)
            / (PERIOD / 4)
        )
        + 1
    )
    cruising = velocities[ramp:]
    assert min(cruising) == max(cruising) == speed  # never brakes between set-points
    assert all(b >= a for a, b in itertools.pairwise(velocities))  # ramps up once


def test_a_new_profile_velocity_is_reached_from_the_present_one(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    start = motor.get("present_position")
    setpoint(motor, ACCEL, 40, start + 1900)
    clock.advance(1.0)  # cruising at 40
    assert motor.get("present_velocity") == 40
    setpoint(motor, ACCEL, 80, start + 1900)
    assert motor.get("present_velocity") == 40  # no jump, no stop
    change = 40 * TICKS_PER_S_PER_VELOCITY_UNIT / (ACCEL * TICKS_PER_S2_PER_ACCELERATION_UNIT)
    clock.advance(0.5 * change)
    assert motor.get("present_velocity") == pytest.approx(60, abs=1)  # half-way up the ramp
    clock.advance(0.5 * change + 0.01)
    assert motor.get("present_velocity") == 80


def test_the_motor_remembers_where_it_was_along_streamed_set_points(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    """A detector's window long past reads the pose along the set-points then."""
    start = motor.get("present_position")
    seen = []
    for k in range(200):
        setpoint(motor, ACCEL, 40, start + 5 * k + 50)
        clock.advance(PERIOD / 2)
        seen.append((clock.now(), motor.position_at(clock.now())))
        clock.advance(PERIOD / 2)
    for t, position in seen:
        assert motor.position_at(t) == position
