"""The emulated bus byte by byte over its pty: e-manual vectors, bus rules, faults."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import pytest

from sim.peers.dynamixel.emulator import DxlEmulator, Fault
from sim.peers.dynamixel.faults import NOISE
from sim.peers.dynamixel.protocol import (
    ALERT,
    BROADCAST_ID,
    Instruction,
    StatusError,
    crc16,
    instruction_packet,
    parse,
    status_packet,
)
from tests.sim.conftest import RawLink

Emulator = Callable[..., DxlEmulator]
Link = Callable[..., RawLink]


def hx(text: str) -> bytes:
    return bytes.fromhex(text)


OK_STATUS_1 = hx("FF FF FD 00 01 04 00 55 00 A1 0C")  # ID 1, no error, no parameters
PING_1 = status_packet(1, 0, hx("FC 03 2E"))  # ID 1, XM430-W350, firmware 46


def read_packet(motor_id: int, address: int, length: int) -> bytes:
    params = address.to_bytes(2, "little") + length.to_bytes(2, "little")
    return instruction_packet(motor_id, Instruction.READ, params)


def write_packet(motor_id: int, address: int, data: bytes) -> bytes:
    return instruction_packet(motor_id, Instruction.WRITE, address.to_bytes(2, "little") + data)


# -- e-manual vectors ---------------------------------------------------------------------


def test_ping_vector_of_the_e_manual(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((1,), model=1030, firmware=38))
    reply = link.transact(hx("FF FF FD 00 01 03 00 01 19 4E"), 14)
    assert reply == hx("FF FF FD 00 01 07 00 55 00 06 04 26 65 5D")


def test_ping_reply_carries_model_and_firmware(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((1,)))  # XM430-W350 (1020 = 0x03FC), firmware 46 (0x2E)
    reply = link.transact(hx("FF FF FD 00 01 03 00 01 19 4E"), 14)
    head = hx("FF FF FD 00 01 07 00 55 00 FC 03 2E")
    crc = crc16(head)
    assert reply == head + bytes([crc & 0xFF, crc >> 8])


def test_broadcast_ping_vector_every_motor_in_id_order(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((2, 1), model=1030, firmware=38))
    reply = link.transact(hx("FF FF FD 00 FE 03 00 01 31 42"), 28)
    assert reply == hx(
        "FF FF FD 00 01 07 00 55 00 06 04 26 65 5D FF FF FD 00 02 07 00 55 00 06 04 26 6F 6D"
    )


def test_read_vector_present_position_166(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    emu.motors[1].set("present_position", 166)
    reply = raw_link(emu).transact(hx("FF FF FD 00 01 07 00 02 84 00 04 00 1D 15"), 15)
    assert reply == hx("FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0")


def test_write_vector_goal_position_512(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    reply = raw_link(emu).transact(hx("FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89"), 11)
    assert reply == OK_STATUS_1
    assert emu.motors[1].get("goal_position") == 512


def test_reg_write_and_action_vectors(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    reg = hx("FF FF FD 00 01 09 00 04 68 00 C8 00 00 00 AE 8E")
    assert link.transact(reg, 11) == OK_STATUS_1
    assert emu.motors[1].get("registered_instruction") == 1
    assert emu.motors[1].get("goal_velocity") == 0
    assert link.transact(hx("FF FF FD 00 01 03 00 05 02 CE"), 11) == OK_STATUS_1
    assert emu.motors[1].get("goal_velocity") == 200
    assert emu.motors[1].get("registered_instruction") == 0


def test_factory_reset_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((3,))
    emu.motors[3].set("id", 1)  # the vector is addressed to ID 1
    emu.motors[1].set("return_delay_time", 0)
    reply = raw_link(emu).transact(hx("FF FF FD 00 01 04 00 06 01 A1 E6"), 11)
    assert reply == OK_STATUS_1
    assert emu.motors[1].get("return_delay_time") == 250


def test_reboot_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    emu.motors[1].set("led", 1)
    reply = raw_link(emu).transact(hx("FF FF FD 00 01 03 00 08 2F 4E"), 11)
    assert reply == OK_STATUS_1
    assert emu.motors[1].get("led") == 0


def test_clear_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    emu.motors[1].set("present_position", 10_000)
    reply = raw_link(emu).transact(hx("FF FF FD 00 01 08 00 10 01 44 58 4C 22 B1 DC"), 11)
    assert reply == OK_STATUS_1
    assert emu.motors[1].get("present_position") == 10_000 - 2 * 4096


def test_sync_read_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    emu.motors[1].set("present_position", 166)
    emu.motors[2].set("present_position", 2079)
    reply = raw_link(emu).transact(hx("FF FF FD 00 FE 09 00 82 84 00 04 00 01 02 CE FA"), 30)
    assert reply == hx(
        "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0 FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE"
    )


def test_sync_write_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    packet = hx("FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87")
    link = raw_link(emu)
    assert link.transact(packet + instruction_packet(1, Instruction.PING), 14) == PING_1
    assert emu.motors[1].get("goal_position") == 150
    assert emu.motors[2].get("goal_position") == 170


def test_bulk_read_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    emu.motors[1].set("present_input_voltage", 119)
    emu.motors[2].set("present_temperature", 36)
    packet = hx("FF FF FD 00 FE 0D 00 92 01 90 00 02 00 02 92 00 01 00 1A 05")
    reply = raw_link(emu).transact(packet, 25)
    assert reply == hx("FF FF FD 00 01 06 00 55 00 77 00 C3 69 FF FF FD 00 02 05 00 55 00 24 8B A9")


def test_bulk_write_vector(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    emu.motors[1].set("max_voltage_limit", 140)
    emu.motors[2].set("temperature_limit", 70)
    packet = hx("FF FF FD 00 FE 10 00 93 01 20 00 02 00 A0 00 02 1F 00 01 00 50 B7 68")
    link = raw_link(emu)
    assert link.transact(packet + instruction_packet(1, Instruction.PING), 14) == PING_1
    assert emu.motors[1].get("max_voltage_limit") == 160
    assert emu.motors[2].get("temperature_limit") == 80


def test_fast_sync_read_is_one_chained_status_packet(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2, 3))
    for motor_id, position in ((1, 166), (2, 2079), (3, -5)):
        emu.motors[motor_id].set("present_position", position)
    params = hx("84 00 04 00 01 02 03")
    reply = raw_link(emu).transact(instruction_packet(BROADCAST_ID, 0x8A, params), 32)
    # LEN = INST + 3 × (ERR + ID + 4 data + CRC) = 25 (the e-manual's example length).
    expected = bytearray(hx("FF FF FD 00 FE 19 00 55"))
    for motor_id, position in ((1, 166), (2, 2079), (3, -5)):
        expected += bytes([0, motor_id]) + position.to_bytes(4, "little", signed=True)
        crc = crc16(bytes(expected))
        expected += bytes([crc & 0xFF, crc >> 8])
    assert reply == bytes(expected)


# -- bus rules ----------------------------------------------------------------------------


def test_a_host_crc_error_is_answered_with_a_crc_error(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    packet = parse(link.transact(hx("FF FF FD 00 01 03 00 01 19 4F"), 11))
    assert (packet.id, packet.error, packet.params) == (1, StatusError.CRC, b"")
    assert emu.stats.crc_errors == 1


def test_unknown_instruction_and_wrong_lengths(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((1,)))
    assert [p.error for p in link.packets(instruction_packet(1, 0x42))] == [StatusError.INSTRUCTION]
    bad_read = instruction_packet(1, Instruction.READ, hx("84 00 04"))
    assert [p.error for p in link.packets(bad_read)] == [StatusError.DATA_LENGTH]
    bad_write = instruction_packet(1, Instruction.WRITE, hx("74 00"))
    assert [p.error for p in link.packets(bad_write)] == [StatusError.DATA_LENGTH]
    assert [p.error for p in link.packets(read_packet(1, 655, 10))] == [StatusError.ACCESS]
    assert [p.error for p in link.packets(read_packet(1, 0, 0))] == [StatusError.DATA_LENGTH]
    action = instruction_packet(1, Instruction.ACTION)
    assert [p.error for p in link.packets(action)] == [StatusError.INSTRUCTION]


def test_write_errors_come_back_in_the_status(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((1,)))
    assert parse(link.transact(write_packet(1, 64, b"\x01"), 11)).error == 0
    eeprom = write_packet(1, 9, b"\x00")
    assert parse(link.transact(eeprom, 11)).error == StatusError.ACCESS
    too_far = write_packet(1, 116, (5000).to_bytes(4, "little"))
    assert parse(link.transact(too_far, 11)).error == StatusError.DATA_LIMIT


@pytest.mark.parametrize(
    ("level", "ping", "read", "write"),
    [(0, True, False, False), (1, True, True, False), (2, True, True, True)],
)
def test_status_return_level(
    emulator: Emulator, raw_link: Link, level: int, ping: bool, read: bool, write: bool
) -> None:
    emu = emulator((1, 2))
    emu.motors[1].set("status_return_level", level)
    link = raw_link(emu)
    assert bool(link.packets(instruction_packet(1, Instruction.PING))) is ping
    assert bool(link.packets(read_packet(1, 132, 4))) is read
    sync_read = instruction_packet(BROADCAST_ID, Instruction.SYNC_READ, hx("84 00 04 00 01 02"))
    assert [p.id for p in link.packets(sync_read)] == ([1, 2] if read else [2])
    assert bool(link.packets(write_packet(1, 65, b"\x01"))) is write
    assert emu.motors[1].get("led") == 1  # executed either way


def test_broadcast_gets_no_status_except_ping_and_reads(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2, 3))
    link = raw_link(emu)
    assert link.packets(write_packet(BROADCAST_ID, 65, b"\x01")) == []
    assert all(m.get("led") == 1 for m in emu.motors.values())
    assert link.packets(read_packet(BROADCAST_ID, 132, 4)) == []
    assert link.packets(instruction_packet(BROADCAST_ID, Instruction.REBOOT)) == []
    assert all(m.get("led") == 0 for m in emu.motors.values())
    pings = link.packets(instruction_packet(BROADCAST_ID, Instruction.PING))
    assert [p.id for p in pings] == [1, 2, 3]


def test_broadcast_factory_reset_all_is_ignored(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((4,))
    link = raw_link(emu)
    link.packets(instruction_packet(BROADCAST_ID, Instruction.FACTORY_RESET, b"\xff"))
    assert emu.motors[4].get("id") == 4
    link.packets(instruction_packet(BROADCAST_ID, Instruction.FACTORY_RESET, b"\x02"))
    assert emu.motors[4].get("id") == 4
    link.packets(instruction_packet(4, Instruction.FACTORY_RESET, b"\xff"))
    assert list(emu.motors) == [1]


def test_an_id_change_answers_with_the_old_id(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    link = raw_link(emu)
    replies = link.packets(write_packet(1, 7, b"\x09"))
    assert [(p.id, p.error) for p in replies] == [(1, 0)]
    assert sorted(emu.motors) == [2, 9]
    assert [p.id for p in link.packets(instruction_packet(9, Instruction.PING))] == [9]
    assert link.packets(instruction_packet(1, Instruction.PING)) == []


def test_secondary_id_executes_without_status(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2, 3))
    for motor in emu.motors.values():
        motor.set("secondary_id", 3)
    link = raw_link(emu)
    replies = link.packets(write_packet(3, 65, b"\x01"))
    assert [p.id for p in replies] == [3]  # only the primary ID answers
    assert all(m.get("led") == 1 for m in emu.motors.values())
    link.packets(write_packet(3, 9, b"\x00"))  # EEPROM through the secondary ID: refused
    assert [m.get("return_delay_time") for m in emu.motors.values()] == [250, 250, 0]


def test_a_motor_switched_to_protocol_1_goes_silent(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    assert link.packets(write_packet(1, 13, b"\x01"))[0].error == 0
    assert link.packets(instruction_packet(1, Instruction.PING)) == []


def test_baud_mismatch_means_silence(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2), baud=57_600)
    link = raw_link(emu, baud=115_200)
    assert emu.host_baud() == 115_200
    assert link.packets(instruction_packet(1, Instruction.PING)) == []
    emu.motors[2].set("baud_rate", 2)  # only motor 2 now speaks 115200
    assert [p.id for p in link.packets(instruction_packet(BROADCAST_ID, 1))] == [2]


def test_baud_rate_change_takes_effect_after_the_status(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,), baud=57_600)
    link = raw_link(emu)
    replies = link.packets(write_packet(1, 8, b"\x03"))  # 1 Mbit/s
    assert [(p.id, p.error) for p in replies] == [(1, 0)]
    assert link.packets(instruction_packet(1, Instruction.PING)) == []
    link.set_baud(1_000_000)
    assert emu.host_baud() == 1_000_000
    assert [p.id for p in link.packets(instruction_packet(1, Instruction.PING))] == [1]


def test_the_rate_of_a_pty_can_be_any_x_series_rate(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    for code, rate in ((0, 9600), (3, 1_000_000), (6, 4_000_000), (7, 4_500_000)):
        emu.motors[1].set("baud_rate", code)
        link.set_baud(rate)
        assert emu.host_baud() == rate
        assert [p.id for p in link.packets(instruction_packet(1, Instruction.PING))] == [1]


def test_noise_between_packets_is_skipped(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    replies = link.packets(b"\x00\xff\xff\x13garbage" + instruction_packet(1, Instruction.PING))
    assert [p.id for p in replies] == [1]


def test_status_packets_on_the_bus_are_ignored(emulator: Emulator, raw_link: Link) -> None:
    link = raw_link(emulator((1,)))
    assert link.packets(status_packet(1, 0, b"\x01")) == []


# -- timing -------------------------------------------------------------------------------


def round_trip(link: RawLink, packet: bytes, expect: int) -> float:
    start = time.perf_counter()
    reply = link.transact(packet, expect)
    elapsed = time.perf_counter() - start
    assert len(reply) == expect
    return elapsed


def test_wire_time_and_return_delay(emulator: Emulator, raw_link: Link) -> None:
    """The delays are lower bounds of the real round trip (a busy machine only adds to
    them). Without them the emulator answers at once; that is checked at 9600 baud,
    where the modelled delay (25.5 ms) is far above a thread switch on a busy machine,
    as the best of five tries under half of it — a broken switch never gets there."""
    ping = instruction_packet(1, Instruction.PING)
    fast = raw_link(emulator((1,), baud=9600, wire_time=False, return_delay=False))
    slow_emu = emulator((1,), baud=9600, wire_time=True, return_delay=True)
    slow = raw_link(slow_emu)
    # 10 bytes out and 14 back at 9600 baud (10 bits each), plus 250 × 2 µs.
    expected = (10 + 14) * 10 / 9600 + 500e-6
    assert min(round_trip(slow, ping, 14) for _ in range(3)) >= expected
    assert min(round_trip(fast, ping, 14) for _ in range(5)) < expected / 2
    slow_emu.motors[1].set("return_delay_time", 0)
    assert min(round_trip(slow, ping, 14) for _ in range(3)) >= expected - 500e-6


# -- faults -------------------------------------------------------------------------------


def test_no_reply_counts_down(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    link = raw_link(emu)
    emu.inject(Fault.NO_REPLY, motor_id=1, count=2)
    ping1, ping2 = instruction_packet(1, 1), instruction_packet(2, 1)
    assert link.packets(ping1) == []
    assert [p.id for p in link.packets(ping2)] == [2]
    assert link.packets(ping1) == []
    assert [p.id for p in link.packets(ping1)] == [1]


def test_reply_faults_change_the_bytes(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    ping = instruction_packet(1, Instruction.PING)
    good = link.transact(ping, 14)
    emu.inject(Fault.CORRUPT_CRC, motor_id=1)
    corrupt = link.transact(ping, 14)
    assert corrupt[:-2] == good[:-2] and corrupt[-2:] != good[-2:]
    emu.inject(Fault.GARBAGE, motor_id=1)
    assert link.transact(ping, len(NOISE) + 14) == NOISE + good
    emu.inject(Fault.WRONG_ID, motor_id=1)
    assert parse(link.transact(ping, 14)).id == 129
    assert link.transact(ping, 14) == good


def test_faults_for_every_motor_and_clearing(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    link = raw_link(emu)
    emu.inject(Fault.NO_REPLY, count=None)
    broadcast_ping = instruction_packet(BROADCAST_ID, Instruction.PING)
    assert link.packets(broadcast_ping) == []
    assert link.packets(broadcast_ping) == []
    emu.clear_faults()
    assert [p.id for p in link.packets(broadcast_ping)] == [1, 2]


def test_silent_bus_hears_nothing(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    emu.inject(Fault.SILENT)
    assert link.packets(write_packet(1, 65, b"\x01")) == []
    assert emu.motors[1].get("led") == 0  # not even executed
    emu.clear_faults()
    assert [p.error for p in link.packets(write_packet(1, 65, b"\x01"))] == [0]


def test_a_hardware_alert_sets_the_alert_bit_until_reboot(
    emulator: Emulator, raw_link: Link
) -> None:
    emu = emulator((1, 2))
    link = raw_link(emu)
    link.packets(write_packet(1, 64, b"\x01"))
    emu.inject(Fault.OVERHEATING, motor_id=1)
    status = link.packets(read_packet(1, 70, 1))[0]
    assert (status.error, status.params) == (ALERT, b"\x04")
    assert link.packets(read_packet(1, 64, 1))[0].params == b"\x00"  # torque went off
    refused = link.packets(write_packet(1, 64, b"\x01"))[0]
    assert refused.error == ALERT | StatusError.RESULT_FAIL
    assert link.packets(instruction_packet(2, Instruction.PING))[0].error == 0
    assert link.packets(instruction_packet(1, Instruction.REBOOT))[0].error == ALERT
    assert link.packets(instruction_packet(1, Instruction.PING))[0].error == 0


def test_clear_faults_can_clear_alerts(emulator: Emulator) -> None:
    emu = emulator((1,))
    emu.inject(Fault.INPUT_VOLTAGE)
    emu.clear_faults()
    assert emu.motors[1].hardware_error == 0x01
    emu.clear_faults(alerts=True)
    assert emu.motors[1].hardware_error == 0


def test_inject_refuses_unknown_motors_and_counts(emulator: Emulator) -> None:
    emu = emulator((1,))
    with pytest.raises(KeyError):
        emu.inject(Fault.NO_REPLY, motor_id=7)
    with pytest.raises(ValueError, match="count"):
        emu.inject(Fault.NO_REPLY, motor_id=1, count=0)


def test_fast_sync_read_with_a_lost_block_is_truncated(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2))
    emu.inject(Fault.NO_REPLY, motor_id=2)
    packet = instruction_packet(BROADCAST_ID, 0x8A, hx("84 00 04 00 01 02"))
    reply = raw_link(emu).transact(packet, 100, timeout=0.05)
    assert len(reply) == 8 + 8  # header and ID 1's block; the LEN still promises ID 2's


def test_a_raw_exchange_waits_until_the_emulator_has_served_it(
    emulator: Emulator, raw_link: Link
) -> None:
    """A reply sent 150 ms late (past any fixed read window a raw test would pick) is
    the exchange's answer: the link waits until the emulator says it has served the
    packet, then reads exactly what it wrote; a packet without a reply reads nothing."""
    emu = emulator((1,))
    link = raw_link(emu)
    ping = instruction_packet(1, Instruction.PING)
    emu.inject(Fault.LATE, motor_id=1, delay_ms=150.0)
    start = time.monotonic()
    assert [(p.id, p.error, p.params) for p in link.packets(ping)] == [(1, 0, hx("FC 03 2E"))]
    assert time.monotonic() - start >= 0.15
    assert emu.stats.late == 1
    assert link.packets(instruction_packet(2, Instruction.PING)) == []  # no motor 2
    assert emu.totals() == (20, 14)  # two pings heard, one reply said


def test_a_stale_reply_comes_before_the_answer(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1,))
    link = raw_link(emu)
    ping = instruction_packet(1, Instruction.PING)
    emu.inject(Fault.STALE, motor_id=1)  # nothing answered yet: nothing stale to send
    assert link.transact(ping, 14) == PING_1
    answer = status_packet(1, 0, hx("00 08 00 00"))  # Present Position 2048
    emu.inject(Fault.STALE, motor_id=1)
    assert link.transact(read_packet(1, 132, 4), 14 + 15) == PING_1 + answer


# -- byte stuffing ------------------------------------------------------------------------

#: -131073 (FF FF FD FF little endian) into Homing Offset (address 20).
HEADER_VALUE = hx("FF FF FD FF")


def test_a_stuffed_write_is_unstuffed_and_the_status_stuffed(
    emulator: Emulator, raw_link: Link
) -> None:
    emu = emulator((1,), record=True)
    link = raw_link(emu)
    packet = write_packet(1, 20, HEADER_VALUE)
    assert hx("FF FF FD FD FF") in packet  # our codec stuffs
    assert [p.error for p in link.packets(packet)] == [0]
    assert emu.motors[1].get("homing_offset") == -131073
    reply = link.transact(read_packet(1, 20, 4), 16)
    assert hx("55 00 FF FF FD FD FF") in reply  # the status is stuffed too
    assert parse(reply).params == HEADER_VALUE


def test_an_unstuffed_header_inside_a_packet_is_a_corrupt_packet(
    emulator: Emulator, raw_link: Link
) -> None:
    """FF FF FD must be followed by the stuffing FD; a packet with a valid CRC but an
    unstuffed FF FF FD (what the SDK sends, see test_sdk_against_emulator) is refused
    like a corrupt one: CRC error, nothing written."""
    emu = emulator((1,))
    link = raw_link(emu)
    body = bytes([Instruction.WRITE, 20, 0]) + HEADER_VALUE
    head = hx("FF FF FD 00 01") + (len(body) + 2).to_bytes(2, "little") + body
    crc = crc16(head)
    unstuffed = head + bytes([crc & 0xFF, crc >> 8])
    replies = link.packets(unstuffed)
    assert [(p.id, p.error) for p in replies] == [(1, StatusError.CRC)]
    assert emu.motors[1].get("homing_offset") == 0
    assert (emu.stats.stuffing_errors, emu.stats.crc_errors) == (1, 0)


# -- statistics, transcript, lifecycle ----------------------------------------------------


def test_stats_and_transcript(emulator: Emulator, raw_link: Link) -> None:
    emu = emulator((1, 2), record=True)
    link = raw_link(emu)
    ping = instruction_packet(1, Instruction.PING)
    sync_read = instruction_packet(BROADCAST_ID, Instruction.SYNC_READ, hx("84 00 04 00 01 02"))
    link.packets(ping)
    link.packets(sync_read)
    stats = emu.stats
    assert (stats.packets_in, stats.packets_out) == (2, 3)
    assert stats.bytes_in == len(ping) + len(sync_read)
    assert stats.bytes_out == 14 + 2 * 15
    assert stats.instructions == {"PING": 1, "SYNC_READ": 1}
    transcript = emu.transcript
    assert transcript[0] == ("rx", ping)
    assert [d for d, _ in transcript] == ["rx", "tx", "rx", "tx", "tx"]
    emu.reset_stats()
    assert emu.stats.packets_in == 0


def serving_threads(start: Callable[[], object]) -> list[threading.Thread]:
    """The threads ``start()`` left running (an emulator's serving thread)."""
    before = set(threading.enumerate())
    start()
    return [t for t in threading.enumerate() if t not in before]


def test_lifecycle() -> None:
    """`stop` ends the serving thread (woken at once, not abandoned to the join's
    timeout) and may be called again."""
    emu = DxlEmulator(ids=(1,), wire_time=False)
    with pytest.raises(RuntimeError):
        _ = emu.path
    before = set(threading.enumerate())
    with emu:
        assert emu.path.startswith("/dev/")
        with pytest.raises(RuntimeError, match="already"):
            emu.start()
        threads = [t for t in threading.enumerate() if t not in before]
        assert len(threads) == 1 and threads[0].is_alive()
    assert not threads[0].is_alive()
    emu.stop()


def test_stop_does_not_hang_while_the_host_is_not_reading() -> None:
    """Replies pile up unread in the pty, more still owed: the serving thread, busy
    delivering them, ends when stopped (a thread left hanging would still be alive)."""
    emu = DxlEmulator(ids=(1,), wire_time=True)
    threads = serving_threads(emu.start)
    link = RawLink(emu.path, emu.baud)
    try:
        for _ in range(200):
            link.send(instruction_packet(BROADCAST_ID, Instruction.PING))
        deadline = time.monotonic() + 10.0  # only a guard: ~20 ms of wire time is needed
        while emu.stats.packets_out < 8 and time.monotonic() < deadline:
            time.sleep(0.002)
        assert emu.stats.packets_out >= 8  # unread replies in the pty (the rest ~0.5 s off)
        emu.stop()
        assert [t.is_alive() for t in threads] == [False]
        assert emu.error is None
    finally:
        emu.stop()
        link.close()


def test_constructor_rejects_bad_ids_and_rates() -> None:
    with pytest.raises(ValueError, match="ids"):
        DxlEmulator(ids=(1, 1))
    with pytest.raises(ValueError, match="ids"):
        DxlEmulator(ids=(253,))
    with pytest.raises(ValueError, match="baud"):
        DxlEmulator(ids=(1,), baud=38_400)
