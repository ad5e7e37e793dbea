"""`DynamixelBus.recover` through the real driver on the emulator's pty: a motor
rebooted while still hot keeps its error (`MotorFault`), one rebooted once cool comes
back in exactly the configuration `open` gave it; a multi-turn motor loses its turn
count in the reboot, which the recovered positions show; `health` reads the load."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.errors import MotorFault
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator

#: What `open` configures, and a reboot resets to factory values unless restored.
CONFIGURED = (
    "operating_mode", "drive_mode", "min_position_limit", "max_position_limit",
    "profile_velocity", "profile_acceleration", "torque_enable",
)  # fmt: skip

Emulator = Callable[..., DxlEmulator]


def axes() -> list[AxisConfig]:
    return [
        AxisConfig(
            name="arm", motor_id=1, min_rad=-1.0, max_rad=1.0, zero_offset_rad=-math.pi,
            profile_velocity_rad_s=2.0, profile_acceleration_rad_s2=20.0,
        ),
        AxisConfig(
            name="turntable", motor_id=2, min_rad=-6.0, max_rad=6.0, mode="extended_position",
            profile_velocity_rad_s=4.0, profile_acceleration_rad_s2=40.0,
        ),
    ]  # fmt: skip


def registers(emu: DxlEmulator, motor_id: int) -> dict[str, int]:
    return {name: emu.motors[motor_id].get(name) for name in CONFIGURED}


def test_a_hot_motor_keeps_its_error_until_it_has_cooled_then_comes_back_configured(
    emulator: Emulator, latency_timer: int, clock: ManualClock
) -> None:
    emu = emulator(ids=(1, 2))
    with DynamixelBus(emu.path, axes(), latency_ms=latency_timer) as bus:
        bus.health()  # a read: the writes of opening have been served
        opened = registers(emu, 1)
        emu.motors[1].heat(85.0, 60.0)  # overheating: latched, torque off
        health = bus.health()["arm"]
        assert health.error_flags == ("overheating",) and health.temperature_c == 85.0
        assert health.load_pct == 0.0 and bus.health()["turntable"].ok
        with pytest.raises(MotorFault, match="overheating"):
            bus.recover("arm")  # still above the 80 °C limit after the reboot
        clock.advance(60.0)  # 30 + 55/e = 50 °C
        recovered = bus.recover("arm")
        assert recovered.position_rad == recovered.held_rad
        assert opened["torque_enable"] == 1
        assert registers(emu, 1) == opened  # mode, limits, profile, torque: as opened
        assert bus.health()["arm"].ok and bus.health()["arm"].temperature_c == 50.0


def test_a_multi_turn_motor_comes_back_within_one_turn(
    emulator: Emulator, latency_timer: int, clock: ManualClock
) -> None:
    emu = emulator(ids=(1, 2))
    with DynamixelBus(emu.path, axes(), latency_ms=latency_timer) as bus:
        bus.move_to({"turntable": -1.0})
        bus.health()  # a read: the goal has been served, before time moves on
        clock.advance(5.0)
        bus.wait_settled(1.0)
        recovered = bus.recover("turntable")
        assert recovered.held_rad == pytest.approx(-1.0, abs=2e-3)
        assert recovered.position_rad == pytest.approx(2 * math.pi - 1.0, abs=2e-3)


def test_the_load_is_the_present_current_over_the_largest_current_limit(
    emulator: Emulator, latency_timer: int
) -> None:
    emu = emulator(ids=(1, 2))
    with DynamixelBus(emu.path, axes(), latency_ms=latency_timer) as bus:
        emu.motors[2].set("present_current", -597)
        assert bus.health()["turntable"].load_pct == pytest.approx(-100 * 597 / 1193)
