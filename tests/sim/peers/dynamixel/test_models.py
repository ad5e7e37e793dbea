"""An emulated motor answers as its model: its table, ranges, defaults and modes."""

import pytest

from sim.clock import ManualClock
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import StatusError


def motor(model: int) -> EmulatedMotor:
    return EmulatedMotor(1, model=model, clock=ManualClock())


def test_an_xl430_refuses_a_register_it_does_not_have() -> None:
    xl430 = motor(1060)
    assert xl430.write(38, (100).to_bytes(2, "little")) == StatusError.ACCESS  # Current Limit
    assert xl430.write(102, (10).to_bytes(2, "little")) == StatusError.ACCESS  # Goal Current
    assert motor(1020).write(38, (100).to_bytes(2, "little")) == StatusError.NONE
    assert xl430.get("temperature_limit") == 72


@pytest.mark.parametrize(
    ("model", "mode", "error"),
    [(1060, 0, StatusError.DATA_RANGE), (1060, 5, StatusError.DATA_RANGE),
     (1060, 16, StatusError.NONE), (1200, 5, StatusError.NONE), (1020, 0, StatusError.NONE)],
)  # fmt: skip
def test_operating_modes_are_the_models(model: int, mode: int, error: StatusError) -> None:
    assert motor(model).write(11, bytes([mode])) == error


def test_an_xl330_accepts_its_own_ranges_and_starts_at_its_defaults() -> None:
    xl330 = motor(1200)
    assert (xl330.get("current_limit"), xl330.get("velocity_limit")) == (1750, 445)
    assert xl330.get("min_voltage_limit") == 35 and xl330.get("max_voltage_limit") == 70
    assert xl330.write(38, (1750).to_bytes(2, "little")) == StatusError.NONE
    assert xl330.write(44, (2047).to_bytes(4, "little")) == StatusError.NONE
    assert xl330.write(34, (35).to_bytes(2, "little")) == StatusError.NONE
    assert xl330.write(38, (1751).to_bytes(2, "little")) == StatusError.DATA_RANGE
    assert motor(1020).write(44, (2047).to_bytes(4, "little")) == StatusError.DATA_RANGE
    assert motor(1220).get("current_limit") == 910  # XC330-T288
    assert xl330.get("goal_current") == 1750  # Goal Current starts at the Current Limit


def test_an_xl330s_table_ends_at_227() -> None:
    xl330 = motor(1200)
    assert xl330.table.size == 228
    assert xl330.write(228, b"\x00") == StatusError.ACCESS
    with pytest.raises(IndexError):
        xl330.read(228, 1)
    # Indirect Address 1 maps Indirect Data 1 (208) onto Present Position's first byte.
    assert xl330.write(168, (132).to_bytes(2, "little")) == StatusError.NONE
    assert xl330.read(208, 1) == xl330.read(132, 1)
    assert xl330.write(168, (228).to_bytes(2, "little")) == StatusError.DATA_RANGE


def test_an_xl330_knows_no_4_5_mbps() -> None:
    with pytest.raises(ValueError, match="not a rate of this model"):
        EmulatedMotor(1, model=1200, baud=4_500_000, clock=ManualClock())
    assert EmulatedMotor(1, model=1020, baud=4_500_000, clock=ManualClock()).baud == 4_500_000


def test_factory_reset_restores_the_models_defaults() -> None:
    xl330 = motor(1200)
    assert xl330.write(44, (1000).to_bytes(4, "little")) == StatusError.NONE
    assert xl330.factory_reset(0x02) == StatusError.NONE
    assert (xl330.get("velocity_limit"), xl330.model) == (445, 1200)
