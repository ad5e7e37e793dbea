"""The emulated motor's heat: Present Temperature falls toward 30 °C on the motor's
clock, and above its Temperature Limit the motor latches Overheating — again after a
REBOOT while still above, as a real motor does."""

from __future__ import annotations

import math

import pytest

from sim.clock import ManualClock
from sim.peers.dynamixel.motor import EmulatedMotor

OVERHEATING = 1 << 2


def test_a_hot_motor_cools_on_its_clock_and_latches_overheating_until_cool(
    clock: ManualClock,
) -> None:
    motor = EmulatedMotor(1, clock=clock)
    motor.set("torque_enable", 1)
    motor.heat(90.0, 100.0)
    assert motor.get("present_temperature") == 90
    assert motor.hardware_error == OVERHEATING  # above the 80 °C limit: latched
    assert motor.get("torque_enable") == 0  # in the Shutdown mask
    clock.advance(20.0)
    expected = 30 + 60 * math.exp(-0.2)  # 79.1 °C: below the limit, the error stays
    assert motor.get("present_temperature") == round(expected)
    assert motor.hardware_error == OVERHEATING
    motor.set("temperature_limit", 70)  # a reboot while above the limit: latched again
    motor.reboot()
    assert motor.hardware_error == OVERHEATING
    clock.advance(100.0)
    motor.reboot()  # cool enough now
    assert motor.hardware_error == 0
    assert motor.get("present_temperature") == round(30 + 60 * math.exp(-1.2))
    clock.advance(2000.0)
    assert motor.get("present_temperature") == 30


def test_heat_needs_a_positive_time_constant(clock: ManualClock) -> None:
    with pytest.raises(ValueError, match="time constant"):
        EmulatedMotor(1, clock=clock).heat(90.0, 0.0)
