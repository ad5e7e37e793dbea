"""The emulated motor without a bus: control-table rules, motion, alerts, resets."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from drivers.dynamixel.control_table import TABLE_SIZE, item
from sim.clock import ManualClock
from sim.peers.dynamixel.motion import ProfileType, classify, move, move_timed, travel_time
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import ALERT, StatusError
from sim.peers.dynamixel.table import EMULATED_TABLE_SIZE, ITEMS

VEL_UNIT = 0.229 * 4096 / 60  # ticks/s per Profile Velocity unit
ACC_UNIT = 214.577 * 4096 / 3600  # ticks/s² per Profile Acceleration unit


def u32(value: int) -> bytes:
    return value.to_bytes(4, "little", signed=value < 0)


@pytest.fixture
def motor(clock: ManualClock) -> EmulatedMotor:
    return EmulatedMotor(1, clock=clock)


def write(motor: EmulatedMotor, name: str, value: int) -> StatusError:
    it = item(name)
    return motor.write(it.address, it.encode(value))


def torque_on(motor: EmulatedMotor) -> None:
    assert write(motor, "torque_enable", 1) == StatusError.NONE


# -- memory and defaults ------------------------------------------------------------------


def test_defaults_follow_the_control_table_and_the_constructor(clock: ManualClock) -> None:
    motor = EmulatedMotor(7, model=1030, firmware=38, baud=1_000_000, clock=clock)
    assert motor.get("model_number") == 1030
    assert motor.get("firmware_version") == 38
    assert motor.get("id") == 7
    assert motor.get("baud_rate") == 3
    assert motor.get("present_input_voltage") == 120
    assert motor.get("present_temperature") == 30
    assert motor.get("shutdown") == 52
    assert motor.get("status_return_level") == 2
    assert motor.get("return_delay_time") == 250
    assert motor.return_delay == pytest.approx(500e-6)
    assert motor.get("present_position") == 2048 == motor.get("goal_position")
    assert motor.get("torque_enable") == 0


def test_the_backdoor_refuses_values_a_register_cannot_hold(motor: EmulatedMotor) -> None:
    too_big = [
        ("goal_position", 1 << 31),
        ("goal_position", (1 << 32) - 1),
        ("present_velocity", -(1 << 31) - 1),
        ("led", 256),
        ("moving", -1),
    ]
    for name, value in too_big:
        with pytest.raises(ValueError, match=name):
            motor.set(name, value)
    assert motor.get("goal_position") == 2048  # nothing was stored
    motor.set("goal_position", -(1 << 31))
    assert motor.get("goal_position") == -(1 << 31)


def test_reads_of_any_range_inside_the_table(motor: EmulatedMotor) -> None:
    whole = motor.read(0, EMULATED_TABLE_SIZE)
    assert len(whole) == EMULATED_TABLE_SIZE == 662
    assert whole[:TABLE_SIZE] == motor.read(0, TABLE_SIZE)
    assert whole[0:2] == (1020).to_bytes(2, "little")
    assert motor.read(14, 6) == bytes(6)  # a reserved gap reads as zeros
    assert motor.read(252, 326) == bytes(326)  # between the two indirect blocks
    with pytest.raises(IndexError):
        motor.read(655, 10)


def test_backdoor_get_and_set(motor: EmulatedMotor) -> None:
    motor.set("present_position", 166)
    assert motor.read(132, 4) == bytes([0xA6, 0, 0, 0])
    motor.set("present_temperature", 70)
    assert motor.get("present_temperature") == 70
    with pytest.raises(KeyError):
        motor.get("no_such_item")
    with pytest.raises(ValueError, match="does not fit"):
        motor.set("led", 300)


# -- write rules --------------------------------------------------------------------------


def test_eeprom_is_locked_while_torque_is_on(motor: EmulatedMotor) -> None:
    torque_on(motor)
    assert write(motor, "return_delay_time", 0) == StatusError.ACCESS
    assert motor.get("return_delay_time") == 250
    assert write(motor, "torque_enable", 0) == StatusError.NONE
    assert write(motor, "return_delay_time", 0) == StatusError.NONE
    assert motor.get("return_delay_time") == 0


@pytest.mark.parametrize("name", ["model_number", "firmware_version", "present_position"])
def test_read_only_items_refuse_writes(motor: EmulatedMotor, name: str) -> None:
    before = motor.get(name)
    it = item(name)
    assert motor.write(it.address, bytes(it.size)) == StatusError.ACCESS
    assert motor.get(name) == before


def test_shape_errors(motor: EmulatedMotor) -> None:
    assert motor.write(116, b"\x00\x02") == StatusError.DATA_LENGTH  # half of Goal Position
    assert motor.write(117, b"\x00\x00\x00\x00") == StatusError.DATA_LENGTH
    assert motor.write(14, b"\x00") == StatusError.ACCESS  # reserved byte
    assert motor.write(146, b"\x00\x00") == StatusError.ACCESS  # past the table
    assert motor.write(64, b"") == StatusError.DATA_LENGTH


@pytest.mark.parametrize(
    ("name", "value"),
    [("id", 253), ("baud_rate", 8), ("led", 2), ("operating_mode", 2), ("drive_mode", 14)],
)
def test_values_outside_an_items_range_are_data_range_errors(
    motor: EmulatedMotor, name: str, value: int
) -> None:
    before = motor.get(name)
    assert write(motor, name, value) == StatusError.DATA_RANGE
    assert motor.get(name) == before


def test_goal_position_limits_in_position_mode(motor: EmulatedMotor) -> None:
    assert write(motor, "max_position_limit", 3000) == StatusError.NONE
    assert write(motor, "min_position_limit", 1000) == StatusError.NONE
    assert write(motor, "goal_position", 3001) == StatusError.DATA_LIMIT
    assert write(motor, "goal_position", 999) == StatusError.DATA_LIMIT
    assert write(motor, "goal_position", 3000) == StatusError.NONE
    assert write(motor, "goal_position", -5) == StatusError.DATA_LIMIT


def test_extended_position_mode_allows_256_turns_each_way(motor: EmulatedMotor) -> None:
    assert write(motor, "operating_mode", 4) == StatusError.NONE
    assert write(motor, "goal_position", -1_048_575) == StatusError.NONE
    assert write(motor, "goal_position", 1_048_575) == StatusError.NONE
    assert write(motor, "goal_position", 1_048_576) == StatusError.DATA_LIMIT
    assert write(motor, "goal_position", -1_048_576) == StatusError.DATA_LIMIT


def test_every_goal_position_written_is_logged_refused_or_not(motor: EmulatedMotor) -> None:
    assert write(motor, "max_position_limit", 3000) == StatusError.NONE
    assert write(motor, "goal_position", 2500) == StatusError.NONE
    assert write(motor, "goal_position", 3001) == StatusError.DATA_LIMIT  # logged all the same
    assert motor.write(108, u32(10) + u32(100) + u32(1500)) == StatusError.NONE  # spanning it
    assert motor.write(116, u32(1700)[:2]) == StatusError.DATA_LENGTH  # half of it: no goal
    assert motor.write(112, u32(100)) == StatusError.NONE  # beside it
    assert motor.reg_write(116, u32(1200)) == StatusError.NONE  # registered, not yet written
    assert motor.goals_written == [2500, 3001, 1500]
    assert motor.action() == StatusError.NONE
    assert motor.goals_written == [2500, 3001, 1500, 1200]
    motor.set("goal_position", 7)  # the backdoor is not the host
    torque_on(motor)  # nor is torque on holding the present position
    motor.clear_goals()
    assert motor.goals_written == []


def test_goal_velocity_current_and_pwm_limits(motor: EmulatedMotor) -> None:
    assert write(motor, "goal_velocity", 200) == StatusError.NONE
    assert write(motor, "goal_velocity", -201) == StatusError.DATA_LIMIT
    assert write(motor, "pwm_limit", 500) == StatusError.NONE
    assert write(motor, "goal_pwm", 501) == StatusError.DATA_LIMIT
    assert write(motor, "goal_current", 1193) == StatusError.NONE


def test_multi_item_writes_are_checked_item_by_item_and_all_or_nothing(
    motor: EmulatedMotor,
) -> None:
    torque_on(motor)
    # Profile Acceleration, Profile Velocity, Goal Position in one 12-byte write.
    assert motor.write(108, u32(10) + u32(100) + u32(3000)) == StatusError.NONE
    assert (motor.get("profile_acceleration"), motor.get("profile_velocity")) == (10, 100)
    assert motor.get("goal_position") == 3000
    assert motor.write(108, u32(20) + u32(200) + u32(5000)) == StatusError.DATA_LIMIT
    assert motor.get("profile_acceleration") == 10  # nothing written
    # Limits written in the same packet as... the EEPROM rule comes first.
    assert motor.write(48, u32(4095) + u32(0)) == StatusError.ACCESS


def test_limits_written_together_count(motor: EmulatedMotor) -> None:
    # Max and Min Position Limit (48, 52) in one write: the new pair is what counts.
    assert motor.write(48, u32(2000) + u32(100)) == StatusError.NONE
    assert write(motor, "goal_position", 2001) == StatusError.DATA_LIMIT


def test_secondary_id_writes_may_not_touch_eeprom(motor: EmulatedMotor) -> None:
    it = item("return_delay_time")
    assert motor.write(it.address, b"\x00", via_secondary=True) == StatusError.ACCESS
    assert motor.write(65, b"\x01", via_secondary=True) == StatusError.NONE


def test_operating_mode_change_resets_profile_and_goal_pwm(motor: EmulatedMotor) -> None:
    assert write(motor, "profile_velocity", 50) == StatusError.NONE
    assert write(motor, "goal_pwm", 100) == StatusError.NONE
    assert write(motor, "operating_mode", 4) == StatusError.NONE
    assert motor.get("profile_velocity") == 0
    assert motor.get("goal_pwm") == 885


@given(
    st.lists(
        st.tuples(st.integers(0, EMULATED_TABLE_SIZE - 1), st.binary(min_size=1, max_size=12)),
        max_size=30,
    )
)
def test_any_sequence_of_writes_keeps_every_item_in_range(
    writes: list[tuple[int, bytes]],
) -> None:
    motor = EmulatedMotor(1, clock=ManualClock())
    for address, data in writes:
        motor.write(address, data)
    for it in ITEMS:
        if it.writable:
            assert it.in_range(motor.get(it.name)), it.name


# -- motion -------------------------------------------------------------------------------


def trapezoid(distance: float, v: float, a: float) -> tuple[float, float]:
    """(acceleration time, total time) of a rest-to-rest move, from the e-manual."""
    t1 = v / a
    if v * t1 >= distance:  # triangular: never reaches v
        t1 = math.sqrt(distance / a)
        return t1, 2 * t1
    return t1, distance / v + t1


def test_trapezoidal_profile_matches_the_closed_form(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    torque_on(motor)
    assert write(motor, "profile_velocity", 100) == StatusError.NONE
    assert write(motor, "profile_acceleration", 20) == StatusError.NONE
    v, a = 100 * VEL_UNIT, 20 * ACC_UNIT
    assert pytest.approx(v / a, rel=1e-3) == 100 / 20 * 0.064  # e-manual: t1 ≈ 64 ms × V/A
    t1, total = trapezoid(3000 - 2048, v, a)

    def expected(t: float) -> float:
        if t <= t1:
            return 2048 + a * t * t / 2
        if t <= total - t1:
            return 2048 + a * t1 * t1 / 2 + v * (t - t1)
        return 3000 - a * (total - t) ** 2 / 2

    start = clock()
    assert write(motor, "goal_position", 3000) == StatusError.NONE
    assert motor.get("moving_status") & 0x30 == ProfileType.TRAPEZOIDAL
    cruise = (t1 + total - t1) / 2
    for t in sorted((0.0, t1 / 2, t1, cruise, total - t1, total - t1 / 2, total - 0.05)):
        clock.advance(start + t - clock())
        assert abs(motor.get("present_position") - expected(t)) <= 0.5 + 1e-9, t
        assert motor.get("moving") == 1
        assert motor.get("moving_status") & 0x03 == 0x02  # profile ongoing, not in position
        if t == cruise:
            assert motor.get("present_velocity") == 100
    clock.advance(start + total - clock())
    assert motor.get("present_position") == 3000
    assert motor.get("moving") == 0
    assert motor.get("present_velocity") == 0
    assert motor.get("moving_status") == ProfileType.TRAPEZOIDAL | 0x01  # in position


def test_triangular_profile(motor: EmulatedMotor, clock: ManualClock) -> None:
    torque_on(motor)
    write(motor, "profile_velocity", 1000)
    write(motor, "profile_acceleration", 5)
    write(motor, "goal_position", 2148)
    a = 5 * ACC_UNIT
    _, total = trapezoid(100, 1000 * VEL_UNIT, a)
    assert total == pytest.approx(2 * math.sqrt(100 / a))
    assert motor.get("moving_status") & 0x30 == ProfileType.TRIANGULAR
    clock.advance(total / 2)
    assert motor.get("present_position") == 2098
    assert motor.get("present_velocity") == round(math.sqrt(a * 100) / VEL_UNIT)
    clock.advance(total / 2)
    assert motor.get("present_position") == 2148
    assert motor.get("moving") == 0


def test_zero_acceleration_is_a_rectangular_profile(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    torque_on(motor)
    write(motor, "profile_velocity", 50)
    write(motor, "goal_position", 1048)
    assert motor.get("moving_status") & 0x30 == ProfileType.RECTANGULAR
    clock.advance(0.5)
    assert motor.get("present_position") == round(2048 - 50 * VEL_UNIT * 0.5)
    assert motor.get("present_velocity") == -50
    clock.advance(1000 / (50 * VEL_UNIT) - 0.5)
    assert motor.get("present_position") == 1048


def test_zero_profile_velocity_moves_at_the_velocity_limit(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    torque_on(motor)
    write(motor, "goal_position", 3048)
    assert motor.get("moving_status") & 0x30 == ProfileType.STEP  # "profile not used"
    limit = motor.get("velocity_limit") * VEL_UNIT
    clock.advance(0.1)
    assert motor.get("present_position") == round(2048 + limit * 0.1)
    clock.advance(1000 / limit)
    assert motor.get("present_position") == 3048


def test_goal_while_torque_off_is_kept_but_not_executed(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    assert write(motor, "goal_position", 1000) == StatusError.NONE
    clock.advance(10)
    assert motor.get("present_position") == 2048
    assert motor.get("goal_position") == 1000
    torque_on(motor)  # the goal becomes the present position: no jump
    clock.advance(10)
    assert motor.get("goal_position") == 2048 == motor.get("present_position")


def test_torque_on_by_goal_update(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "drive_mode", 0x08)
    assert write(motor, "goal_position", 1000) == StatusError.NONE
    assert motor.get("torque_enable") == 1
    clock.advance(5)
    assert motor.get("present_position") == 1000


def test_torque_off_stops_the_motor_where_it_is(motor: EmulatedMotor, clock: ManualClock) -> None:
    torque_on(motor)
    write(motor, "profile_velocity", 10)
    write(motor, "goal_position", 4000)
    clock.advance(1.0)
    here = motor.get("present_position")
    write(motor, "torque_enable", 0)
    clock.advance(10)
    assert motor.get("present_position") == here
    assert motor.get("moving") == 0


def test_extended_mode_goes_negative_and_reboot_keeps_one_turn(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    write(motor, "operating_mode", 4)
    torque_on(motor)
    write(motor, "goal_position", -10_000)
    clock.advance(60)
    assert motor.get("present_position") == -10_000
    assert motor.read(132, 4) == u32(-10_000)
    motor.reboot()
    assert motor.get("present_position") == -10_000 % 4096
    assert motor.shaft_position == pytest.approx(-10_000 % 4096)


def test_position_mode_torque_on_wraps_to_one_turn(motor: EmulatedMotor) -> None:
    write(motor, "operating_mode", 4)
    motor.set("present_position", 5000)
    write(motor, "operating_mode", 3)  # changing to position mode wraps too
    assert motor.get("present_position") == 5000 - 4096
    write(motor, "operating_mode", 4)
    motor.set("present_position", -100)
    write(motor, "operating_mode", 3)
    assert motor.get("present_position") == 3996


def test_reverse_drive_mode_turns_the_other_way(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "operating_mode", 4)
    motor.set("present_position", 0)
    write(motor, "drive_mode", 1)
    assert motor.get("present_position") == 0
    torque_on(motor)
    write(motor, "goal_position", 1000)
    clock.advance(5)
    assert motor.get("present_position") == 1000
    assert motor.shaft_position == pytest.approx(-1000)


def test_homing_offset_is_added_to_the_shaft_angle(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    write(motor, "operating_mode", 4)
    motor.set("present_position", 100)
    write(motor, "homing_offset", 1000)
    assert motor.get("present_position") == 1100
    assert motor.shaft_position == pytest.approx(100)
    write(motor, "drive_mode", 1)  # the offset's sign is not reversed
    assert motor.get("present_position") == -100 + 1000
    torque_on(motor)
    write(motor, "goal_position", 0)
    clock.advance(5)
    assert motor.shaft_position == pytest.approx(1000)


def test_position_mode_ignores_a_homing_offset_beyond_1024(motor: EmulatedMotor) -> None:
    motor.set("present_position", 100)
    assert write(motor, "homing_offset", 2000) == StatusError.NONE
    assert motor.get("present_position") == 100
    assert write(motor, "homing_offset", -50) == StatusError.NONE
    assert motor.get("present_position") == 50


def test_a_new_goal_mid_move_keeps_the_velocity(motor: EmulatedMotor, clock: ManualClock) -> None:
    torque_on(motor)
    write(motor, "profile_velocity", 100)
    write(motor, "profile_acceleration", 20)
    write(motor, "goal_position", 4000)
    clock.advance(0.5)
    speed = motor.get("present_velocity")
    here = motor.get("present_position")
    write(motor, "goal_position", 100)  # behind: brake, turn, come back
    assert motor.get("present_velocity") == speed
    clock.advance(0.01)
    assert motor.get("present_position") > here  # still going forward
    clock.advance(60)
    assert motor.get("present_position") == 100
    assert motor.get("moving") == 0


def test_velocity_mode_ramps_and_spins(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "operating_mode", 1)
    torque_on(motor)
    write(motor, "profile_acceleration", 10)
    write(motor, "goal_velocity", 100)
    ramp = 100 * VEL_UNIT / (10 * ACC_UNIT)
    clock.advance(ramp + 1.0)
    assert motor.get("present_velocity") == 100
    assert motor.get("moving") == 1
    expected = 2048 + 0.5 * 100 * VEL_UNIT * ramp + 100 * VEL_UNIT * 1.0
    assert motor.get("present_position") == round(expected)


def test_realtime_tick_counts_milliseconds_and_wraps(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    clock.advance(1.234)
    assert motor.get("realtime_tick") == 1234
    clock.advance(32.768)
    assert motor.get("realtime_tick") == 1234


# -- alerts, reboot, factory reset, registered writes -------------------------------------


def test_a_shutdown_alert_turns_torque_off_until_reboot(
    motor: EmulatedMotor, clock: ManualClock
) -> None:
    torque_on(motor)
    write(motor, "profile_velocity", 10)
    write(motor, "goal_position", 4000)
    clock.advance(0.5)
    motor.raise_alert(5)  # overload
    here = motor.get("present_position")
    assert motor.hardware_error == 0x20
    assert motor.get("torque_enable") == 0
    assert motor.status_error() == ALERT
    assert motor.status_error(StatusError.DATA_LIMIT) == ALERT | 6
    assert write(motor, "torque_enable", 1) == StatusError.RESULT_FAIL
    assert write(motor, "goal_position", 100) == StatusError.NONE  # stored, not executed
    clock.advance(10)
    assert motor.get("present_position") == here
    motor.reboot()
    assert motor.hardware_error == 0
    assert motor.status_error() == 0
    torque_on(motor)


def test_an_alert_outside_the_shutdown_mask_keeps_torque(motor: EmulatedMotor) -> None:
    torque_on(motor)
    motor.raise_alert(3)  # motor encoder: not in the default mask 52
    assert motor.get("torque_enable") == 1
    assert motor.status_error() == ALERT


def test_reboot_resets_ram_and_keeps_eeprom(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "return_delay_time", 10)
    torque_on(motor)
    write(motor, "led", 1)
    write(motor, "status_return_level", 1)
    clock.advance(3)
    motor.reboot()
    assert motor.get("torque_enable") == 0
    assert motor.get("led") == 0
    assert motor.get("status_return_level") == 2
    assert motor.get("return_delay_time") == 10
    assert motor.get("realtime_tick") == 0


@pytest.mark.parametrize(
    ("option", "expected_id", "expected_baud"), [(0xFF, 1, 1), (0x01, 5, 1), (0x02, 5, 3)]
)
def test_factory_reset_options(
    clock: ManualClock, option: int, expected_id: int, expected_baud: int
) -> None:
    motor = EmulatedMotor(5, baud=1_000_000, clock=clock)
    write(motor, "return_delay_time", 0)
    assert motor.factory_reset(option) == StatusError.NONE
    assert motor.get("id") == expected_id
    assert motor.get("baud_rate") == expected_baud
    assert motor.get("return_delay_time") == 250
    assert motor.get("model_number") == 1020


def test_factory_reset_refuses_unknown_options(motor: EmulatedMotor) -> None:
    assert motor.factory_reset(0x03) == StatusError.DATA_RANGE


def test_reg_write_then_action(motor: EmulatedMotor) -> None:
    assert motor.action() == StatusError.INSTRUCTION
    assert motor.reg_write(65, b"\x01") == StatusError.NONE
    assert motor.get("registered_instruction") == 1
    assert motor.get("led") == 0
    assert motor.action() == StatusError.NONE
    assert motor.get("led") == 1
    assert motor.get("registered_instruction") == 0
    assert motor.reg_write(65, b"\x05") == StatusError.DATA_RANGE


def test_clear_multi_turn_needs_a_motor_at_rest(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "operating_mode", 4)
    torque_on(motor)
    write(motor, "profile_velocity", 10)
    write(motor, "goal_position", 9000)
    assert motor.clear_multi_turn() == StatusError.RESULT_FAIL
    clock.advance(100)
    assert motor.clear_multi_turn() == StatusError.NONE
    assert motor.get("present_position") == 9000 % 4096


# -- the profile math, for any move -------------------------------------------------------

distances = st.floats(-1e6, 1e6, allow_nan=False).filter(lambda d: abs(d) > 1e-3)
speeds = st.one_of(st.just(math.inf), st.floats(1.0, 1e5))
accelerations = st.one_of(st.just(math.inf), st.floats(1.0, 1e6))


@given(distances, speeds, accelerations, st.lists(st.floats(0, 1), min_size=1, max_size=20))
def test_a_move_from_rest_never_overshoots_and_ends_on_time(
    distance: float, v_max: float, a_max: float, fractions: list[float]
) -> None:
    traj = move(0.0, 0.0, distance, v_max, a_max)
    total = travel_time(distance, v_max, a_max)
    assert traj.duration == pytest.approx(total, rel=1e-9, abs=1e-12)
    previous = 0.0
    for t in sorted(f * total * 1.1 for f in fractions):
        position, velocity = traj.at(t)
        assert min(0.0, distance) <= position <= max(0.0, distance)
        assert abs(position) >= abs(previous) - 1e-9 * abs(distance)  # monotone
        assert abs(velocity) <= v_max * (1 + 1e-9)
        previous = position
    assert traj.at(traj.duration) == (distance, 0.0)
    assert traj.at(total)[0] == pytest.approx(distance, rel=1e-9)
    assert traj.kind == classify(distance, v_max, a_max)


@given(
    distances,
    st.floats(-2e4, 2e4),
    st.floats(1.0, 1e4),
    st.floats(1.0, 1e5),
    st.lists(st.floats(0, 1), min_size=1, max_size=20),
)
def test_a_move_from_any_velocity_is_continuous_and_ends_at_rest_on_the_goal(
    goal: float, v0: float, v_max: float, a_max: float, fractions: list[float]
) -> None:
    traj = move(0.0, v0, goal, v_max, a_max)
    assert traj.at(0.0) == pytest.approx((0.0, v0))
    for seg, following in zip(traj.segments, traj.segments[1:], strict=False):
        end = seg.at(seg.duration)
        assert end[0] == pytest.approx(following.position, rel=1e-9, abs=1e-6)
        assert end[1] == pytest.approx(following.velocity, rel=1e-9, abs=1e-6)
    for f in fractions:
        _, velocity = traj.at(f * traj.duration)
        assert abs(velocity) <= max(abs(v0), v_max) * (1 + 1e-9)
    assert traj.at(traj.duration + 1.0) == (goal, 0.0)


def test_timed_profile_takes_the_requested_time() -> None:
    traj = move_timed(0.0, 1000.0, total_s=2.0, accel_s=0.5)
    assert traj.duration == pytest.approx(2.0)
    assert traj.at(1.0)[0] == pytest.approx(500.0)
    assert traj.kind == ProfileType.TRAPEZOIDAL
    assert move_timed(0.0, 1000.0, total_s=1.0, accel_s=0.9).kind == ProfileType.TRIANGULAR


def test_time_based_profile_through_the_registers(motor: EmulatedMotor, clock: ManualClock) -> None:
    write(motor, "drive_mode", 0x04)  # time-based: Profile Velocity/Acceleration in ms
    torque_on(motor)
    write(motor, "profile_velocity", 2000)
    write(motor, "profile_acceleration", 500)
    write(motor, "goal_position", 3048)
    clock.advance(1.0)
    assert motor.get("present_position") == 2548  # half way at half time
    clock.advance(0.999)
    assert motor.get("moving") == 1
    clock.advance(0.001)
    assert motor.get("present_position") == 3048
    assert motor.get("moving") == 0
