"""The control table as data, and axis unit conversions."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import (
    BY_ADDRESS,
    EEPROM_END,
    ITEMS,
    RAD_PER_TICK,
    TABLE_SIZE,
    decode_hardware_error,
    item,
)

REQUIRED = [
    "model_number", "firmware_version", "id", "baud_rate", "return_delay_time", "drive_mode",
    "operating_mode", "homing_offset", "velocity_limit", "max_position_limit",
    "min_position_limit", "shutdown", "torque_enable", "status_return_level",
    "hardware_error_status", "profile_acceleration", "profile_velocity", "goal_position",
    "moving", "present_velocity", "present_position", "present_input_voltage",
    "present_temperature",
]  # fmt: skip


def test_every_required_item_is_there_with_its_e_manual_address() -> None:
    addresses = {
        "model_number": 0, "firmware_version": 6, "id": 7, "baud_rate": 8,
        "return_delay_time": 9, "drive_mode": 10, "operating_mode": 11, "homing_offset": 20,
        "velocity_limit": 44, "max_position_limit": 48, "min_position_limit": 52,
        "shutdown": 63, "torque_enable": 64, "status_return_level": 68,
        "hardware_error_status": 70, "profile_acceleration": 108, "profile_velocity": 112,
        "goal_position": 116, "moving": 122, "present_velocity": 128,
        "present_position": 132, "present_input_voltage": 144, "present_temperature": 146,
    }  # fmt: skip
    for name in REQUIRED:
        assert item(name).address == addresses[name], name


def test_items_do_not_overlap_and_areas_match_addresses() -> None:
    taken: set[int] = set()
    for it in ITEMS:
        span = set(range(it.address, it.address + it.size))
        assert not span & taken, it.name
        taken |= span
        assert (it.address < EEPROM_END) == (it.area.value == "EEPROM"), it.name
        assert it.address + it.size <= TABLE_SIZE
    assert BY_ADDRESS[116].name == "goal_position"


def test_signed_registers_convert_from_the_sdks_unsigned_values() -> None:
    pos = item("present_position")
    assert pos.decode(0xFFFFFFFF) == -1
    assert pos.decode((-123456) & 0xFFFFFFFF) == -123456
    assert pos.encode(-2) == b"\xfe\xff\xff\xff"
    assert item("moving").decode(0xFF) == 255  # unsigned stays unsigned


def test_values_that_do_not_fit_are_value_errors() -> None:
    with pytest.raises(ValueError, match="does not fit"):
        item("led").encode(300)
    position, current, moving = item("goal_position"), item("goal_current"), item("moving")
    for value in (1 << 31, (1 << 32) - 1, -(1 << 31) - 1):  # not a signed 32-bit value
        with pytest.raises(ValueError, match="goal_position"):
            position.encode(value)
    assert position.encode((1 << 31) - 1) == b"\xff\xff\xff\x7f"
    assert position.encode(-(1 << 31)) == b"\x00\x00\x00\x80"
    with pytest.raises(ValueError, match="does not fit"):
        current.encode(40_000)  # signed 16-bit
    with pytest.raises(ValueError, match="does not fit"):
        moving.encode(-1)  # unsigned
    assert item("model_number").encode(65_535) == b"\xff\xff"
    assert not item("operating_mode").in_range(2)
    assert item("operating_mode").in_range(16)
    assert not item("drive_mode").in_range(2)  # bit 1 is unused


def test_unknown_item_names_the_known_ones() -> None:
    with pytest.raises(KeyError, match="goal_position"):
        item("goal_postion")


def test_hardware_error_bits_are_named() -> None:
    assert decode_hardware_error(0) == ()
    assert decode_hardware_error(0b0010_0100) == ("overheating", "overload")
    assert decode_hardware_error(0b0001_1001) == (
        "input_voltage",
        "motor_encoder",
        "electrical_shock",
    )
    assert decode_hardware_error(0b0000_0010) == ("bit1",)


def axis(**kw: object) -> AxisConfig:
    base: dict[str, object] = {
        "name": "a",
        "motor_id": 1,
        "min_rad": -1.0,
        "max_rad": 1.0,
        "zero_offset_rad": -math.pi,
    }
    base.update(kw)
    return AxisConfig(**base)  # type: ignore[arg-type]


@given(
    st.floats(-1.0, 1.0),
    st.sampled_from([1.0, 2.5, 0.5]),
    st.sampled_from([1, -1]),
)
def test_ticks_round_trip_within_half_a_tick(angle: float, gear: float, direction: int) -> None:
    a = axis(gear_ratio=gear, direction=direction, zero_offset_rad=0.0, mode="extended_position")
    assert abs(a.to_rad(a.to_ticks(angle)) - angle) <= 0.5 * RAD_PER_TICK / gear + 1e-15


def test_direction_and_offset() -> None:
    a = axis(direction=-1, zero_offset_rad=math.pi, min_rad=0.5, max_rad=3.0)
    assert a.to_ticks(math.pi) == 0
    assert a.to_ticks(math.pi - RAD_PER_TICK) == 1
    assert a.tick_limits() == (
        math.ceil((math.pi - 3.0) / RAD_PER_TICK),
        math.floor((math.pi - 0.5) / RAD_PER_TICK),
    )


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"min_rad": 1.0, "max_rad": -1.0}, "not below"),
        ({"motor_id": 300}, "0…252"),
        ({"direction": 2}, r"\+1 or -1"),
        ({"gear_ratio": 0.0}, "positive"),
        ({"mode": "velocity"}, "mode"),
        ({"zero_offset_rad": 0.0}, "outside 0…4095"),  # -1 rad needs negative ticks
        ({"max_rad": math.inf}, "finite"),
    ],
)
def test_bad_axis_configuration_is_one_clear_error(kw: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        axis(**kw)


def test_profile_registers_convert_rad_per_second() -> None:
    a = axis(
        profile_velocity_rad_s=1.0,
        profile_acceleration_rad_s2=10.0,
        gear_ratio=2.0,
        mode="extended_position",
    )
    v, acc = a.profile_registers()
    assert v == round(2.0 / (0.229 * 2 * math.pi / 60))
    assert acc == round(20.0 / (214.577 * 2 * math.pi / 3600))
    tiny = axis(profile_velocity_rad_s=1e-9, profile_acceleration_rad_s2=1e-9)
    assert tiny.profile_registers() == (1, 1)


def test_profile_rates_are_the_registers_steps_at_the_axis() -> None:
    """The rates a motor runs: 45 °/s and 90 °/s² on a direct axis are 33 × 0.229 rev/min
    (45.34 °/s) and 4 × 214.577 rev/min² (85.83 °/s²); through a 2:1 gear, 40 °/s and
    60 °/s² are 58 and 6 steps of the motor, halved at the axis."""
    direct = axis(
        profile_velocity_rad_s=math.radians(45), profile_acceleration_rad_s2=math.radians(90)
    )
    v, a = direct.profile_rates()
    assert math.degrees(v) == pytest.approx(33 * 0.229 * 360 / 60, rel=1e-12)
    assert math.degrees(a) == pytest.approx(4 * 214.577 * 360 / 3600, rel=1e-12)
    assert math.degrees(a) == pytest.approx(85.83, abs=0.005)
    geared = axis(
        profile_velocity_rad_s=math.radians(40),
        profile_acceleration_rad_s2=math.radians(60),
        gear_ratio=2.0,
        mode="extended_position",
    )
    v, a = geared.profile_rates()
    assert math.degrees(v) == pytest.approx(58 * 0.229 * 360 / 60 / 2, rel=1e-12)
    assert math.degrees(a) == pytest.approx(6 * 214.577 * 360 / 3600 / 2, rel=1e-12)
