"""The driver on motors of several models: the real SDK over a pty against the emulator,
each motor answering with its model's table."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.models import MODELS
from drivers.errors import DriverError
from sim.peers.dynamixel.emulator import DxlEmulator

Emulator = Callable[..., DxlEmulator]
#: XM430-W350, XL430-W250 (no current registers, 4 modes), XL330-M288 (another table end).
THREE = (1020, 1060, 1200)


def _axes(models: dict[int, int | None]) -> list[AxisConfig]:
    return [
        AxisConfig(f"axis{i}", i, -1.0, 1.0, zero_offset_rad=-math.pi, model=expected)
        for i, expected in models.items()
    ]


@pytest.mark.parametrize("number", THREE)
def test_a_bus_of_one_model_opens_moves_and_reads_health(emulator: Emulator, number: int) -> None:
    emu = emulator(ids=(1, 2), model=number)
    config = _axes({1: number, 2: None})
    with DynamixelBus(emu.path, config, latency_ms=0, clock=emu.clock) as bus:
        assert bus.models == dict.fromkeys(("axis1", "axis2"), MODELS[number].name)
        bus.move_to({"axis1": 0.5, "axis2": -0.5})
        bus.wait_settled(5.0)  # on the emulator's manual clock
        assert bus.positions()["axis1"] == pytest.approx(0.5, abs=2e-3)
        health = bus.health()
    assert {h.load_pct for h in health.values()} == {0.0}
    assert emu.motors[1].get("operating_mode") == 3


def test_an_xl430s_load_comes_from_present_load(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2), model={1: 1060, 2: 1020})
    emu.motors[1].set("present_load", -250)  # −25.0 %
    emu.motors[2].set("present_current", 1193)  # the XM430-W350's full Current Limit
    with DynamixelBus(emu.path, _axes({1: None, 2: None}), latency_ms=0) as bus:
        health = bus.health()
    assert health["axis1"].load_pct == pytest.approx(-25.0)
    assert health["axis2"].load_pct == pytest.approx(100.0)


def test_open_stops_at_a_motor_of_another_model(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2), model={1: 1020, 2: 1060})
    bus = DynamixelBus(emu.path, _axes({1: 1020, 2: 1200}), latency_ms=0)
    before = emu.motors[2].goals_written
    with pytest.raises(DriverError) as caught:
        bus.open()
    message = str(caught.value)
    assert "\n" not in message
    assert "motor 2 (axis 'axis2') is an XL430-W250 (model number 1060)" in message
    assert "expects XL330-M288 (axes.axis2.motor_model)" in message
    assert not bus.is_open and emu.motors[2].goals_written == before
    assert emu.motors[2].get("torque_enable") == 0


def test_the_link_never_sends_a_register_the_model_lacks(emulator: Emulator) -> None:
    emu = emulator(ids=(1,), model="XL430-W250")
    with (
        DynamixelLink(emu.path, latency_ms=0) as link,
        pytest.raises(DriverError, match=r"access error \(.*an address the model lacks"),
    ):
        link.write(1, "current_limit", 100)  # no table known yet: the motor refuses it
    with DynamixelLink(emu.path, latency_ms=0) as link:
        link.tables[1] = MODELS[link.ping(1)]
        before = emu.stats.packets_in
        with pytest.raises(DriverError, match="is an XL430-W250, which has no current_limit"):
            link.write(1, "current_limit", 100)
        with pytest.raises(DriverError, match="which has no goal_current"):
            link.sync_write("goal_current", {1: 10})
        with pytest.raises(DriverError, match="which has no present_current"):
            link.read(1, "present_current")
        assert emu.stats.packets_in == before
        assert link.read(1, "present_load") == 0
