"""Indirect Address/Data and Control Table Backup, through the unmodified ROBOTIS SDK on
the emulator's pty the way a program uses them, and the rules behind them on one motor."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from dynamixel_sdk import (
    COMM_SUCCESS,
    GroupBulkRead,
    GroupBulkWrite,
    GroupSyncRead,
    GroupSyncWrite,
)
from dynamixel_sdk.protocol2_packet_handler import (
    PKT_ID,
    PKT_INSTRUCTION,
    PKT_LENGTH_H,
    PKT_LENGTH_L,
    PKT_PARAMETER0,
)

from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import StatusError
from sim.peers.dynamixel.table import BACKUP_RAM_ITEMS, BY_NAME, INDIRECT_SLOT

Emulator = Callable[..., DxlEmulator]
Port = Callable[..., Any]

GOAL, PRESENT, TORQUE, LED, PROFILE_VELOCITY = 116, 132, 64, 65, 112
RETURN_DELAY, STARTUP, BACKUP_READY = 9, 60, 147
#: Indirect Address n and Indirect Data n of the first block (n = 1..28) and the second
#: (n = 29..56), as the e-manual's X430 control tables place them.
ADDRESS_1, DATA_1, ADDRESS_29, DATA_29 = 168, 224, 578, 634
BACKUP = 0x20


def le(value: int, size: int = 4) -> list[int]:
    return list(value.to_bytes(size, "little", signed=value < 0))


def slots_for(address: int, size: int) -> list[int]:
    """The Indirect Address values that map ``size`` consecutive bytes from ``address``
    (2 bytes each, little endian), ready for one write over consecutive slots."""
    return [byte for a in range(address, address + size) for byte in le(a, 2)]


def backup_packet(ph: Any, port: Any, dxl_id: int, params: bytes) -> tuple[int, int]:
    """CONTROL_TABLE_BACKUP through the SDK's public packet API (it has no helper)."""
    tx = [0] * (PKT_PARAMETER0 + len(params) + 2)
    tx[PKT_ID] = dxl_id
    tx[PKT_LENGTH_L], tx[PKT_LENGTH_H] = le(len(params) + 3, 2)
    tx[PKT_INSTRUCTION] = BACKUP
    tx[PKT_PARAMETER0 : PKT_PARAMETER0 + len(params)] = list(params)
    _, result, error = ph.txRxPacket(port, tx)
    return result, error


STORE, RESTORE = b"\x01CTRL", b"\x02CTRL"


# -- indirect addressing through the SDK ---------------------------------------------------


def test_sync_goals_and_positions_through_indirect_data(
    emulator: Emulator, sdk_port: Port, ph: Any, clock: ManualClock
) -> None:
    """Map Goal Position to Indirect Data 1-4 and Present Position to 5-8 on two motors,
    then move them and read them back through the indirect block only."""
    ids = (1, 2)
    emu = emulator(ids)
    port = sdk_port(emu)
    mapping = GroupSyncWrite(port, ph, ADDRESS_1, 16)
    torque = GroupSyncWrite(port, ph, TORQUE, 1)
    for i in ids:
        assert mapping.addParam(i, slots_for(GOAL, 4) + slots_for(PRESENT, 4))
        assert torque.addParam(i, [1])
    assert mapping.txPacket() == COMM_SUCCESS
    assert torque.txPacket() == COMM_SUCCESS
    assert ph.read2ByteTxRx(port, 2, ADDRESS_1 + 2 * 4) == (PRESENT, COMM_SUCCESS, 0)

    goals = GroupSyncWrite(port, ph, DATA_1, 4)
    for i in ids:
        assert goals.addParam(i, le(1000 * i))
    assert goals.txPacket() == COMM_SUCCESS
    assert ph.read4ByteTxRx(port, 1, GOAL) == (1000, COMM_SUCCESS, 0)  # also a barrier
    assert emu.goals_written() == {1: [1000], 2: [2000]}
    clock.advance(5)

    reader = GroupSyncRead(port, ph, DATA_1, 8)
    for i in ids:
        assert reader.addParam(i)
    assert reader.txRxPacket() == COMM_SUCCESS
    assert [reader.getData(i, DATA_1 + 4, 4) for i in ids] == [1000, 2000]
    assert [reader.getData(i, DATA_1, 4) for i in ids] == [1000, 2000]

    # Plain WRITE and READ through the same slots, and the fast form of the sync read.
    assert ph.write4ByteTxRx(port, 2, DATA_1, 3000) == (COMM_SUCCESS, 0)
    clock.advance(5)
    assert ph.read4ByteTxRx(port, 2, DATA_1 + 4) == (3000, COMM_SUCCESS, 0)
    assert reader.fastSyncRead() == COMM_SUCCESS
    assert [reader.getData(i, DATA_1 + 4, 4) for i in ids] == [1000, 3000]


def test_the_second_block_through_bulk_instructions(
    emulator: Emulator, sdk_port: Port, ph: Any
) -> None:
    """Indirect Address 29-33 (578-586) map Present Position and LED of motor 2 to
    Indirect Data 29-33 (634-638); bulk write and bulk read reach them there."""
    emu = emulator((1, 2))
    port = sdk_port(emu)
    emu.motors[2].set("present_position", 1234)
    mapping = slots_for(PRESENT, 4) + slots_for(LED, 1)
    assert ph.writeTxRx(port, 2, ADDRESS_29, len(mapping), mapping) == (COMM_SUCCESS, 0)
    writer = GroupBulkWrite(port, ph)
    assert writer.addParam(1, LED, 1, [1])
    assert writer.addParam(2, DATA_29 + 4, 1, [1])
    assert writer.txPacket() == COMM_SUCCESS
    reader = GroupBulkRead(port, ph)
    assert reader.addParam(1, LED, 1)
    assert reader.addParam(2, DATA_29, 5)
    assert reader.txRxPacket() == COMM_SUCCESS
    assert reader.getData(1, LED, 1) == 1
    assert (reader.getData(2, DATA_29, 4), reader.getData(2, DATA_29 + 4, 1)) == (1234, 1)
    assert emu.motors[2].get("led") == 1
    assert reader.fastBulkRead() == COMM_SUCCESS
    assert reader.getData(2, DATA_29, 4) == 1234


def test_access_rules_hold_through_the_indirection(
    emulator: Emulator, sdk_port: Port, ph: Any
) -> None:
    emu = emulator((1,))
    port = sdk_port(emu)
    # Defaults: Indirect Address n holds the address of Indirect Data n, which then
    # keeps its own byte; the mapping is RAM, writable with torque on.
    assert ph.read2ByteTxRx(port, 1, ADDRESS_1) == (DATA_1, COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 1, ADDRESS_29 + 2 * 27) == (661, COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, DATA_1, 7) == (COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 1, DATA_1) == (7, COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (COMM_SUCCESS, 0)
    mapping = slots_for(GOAL, 4) + slots_for(PRESENT, 4)
    assert ph.writeTxRx(port, 1, ADDRESS_1, len(mapping), mapping) == (COMM_SUCCESS, 0)
    # Only the RAM area (64-661) may be mapped: EEPROM (Operating Mode, 11) is out of range.
    assert ph.write2ByteTxRx(port, 1, ADDRESS_1 + 2 * 8, 11) == (
        COMM_SUCCESS,
        StatusError.DATA_RANGE,
    )
    assert ph.write2ByteTxRx(port, 1, ADDRESS_1 + 2 * 8, 662)[1] == StatusError.DATA_RANGE
    # A read-only target stays read-only; a 4-byte target needs all four slots at once;
    # the target's limits apply.
    assert ph.write4ByteTxRx(port, 1, DATA_1 + 4, 0)[1] == StatusError.ACCESS
    assert ph.write2ByteTxRx(port, 1, DATA_1, 100)[1] == StatusError.DATA_LENGTH
    assert ph.write4ByteTxRx(port, 1, DATA_1, 5000)[1] == StatusError.DATA_LIMIT
    assert ph.read4ByteTxRx(port, 1, GOAL)[0] == 2048
    # REBOOT puts the mapping (RAM) back to its defaults.
    assert ph.reboot(port, 1) == (COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 1, ADDRESS_1) == (DATA_1, COMM_SUCCESS, 0)


# -- control table backup through the SDK ----------------------------------------------------


def test_backup_store_and_restore_through_the_sdk(
    emulator: Emulator, sdk_port: Port, ph: Any
) -> None:
    emu = emulator((1,), record=True)
    port = sdk_port(emu)
    assert ph.read1ByteTxRx(port, 1, BACKUP_READY) == (0, COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, RETURN_DELAY, 0) == (COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 1, PROFILE_VELOCITY, 100) == (COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 1, ADDRESS_1, GOAL) == (COMM_SUCCESS, 0)
    assert backup_packet(ph, port, 1, STORE) == (COMM_SUCCESS, 0)
    sent = [data for direction, data in emu.transcript if direction == "rx"]
    assert sent[-1].hex(" ").upper() == "FF FF FD 00 01 08 00 20 01 43 54 52 4C 16 F5"
    assert ph.read1ByteTxRx(port, 1, BACKUP_READY) == (1, COMM_SUCCESS, 0)

    assert ph.write1ByteTxRx(port, 1, RETURN_DELAY, 100) == (COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 1, PROFILE_VELOCITY, 5) == (COMM_SUCCESS, 0)
    assert backup_packet(ph, port, 1, RESTORE) == (COMM_SUCCESS, 0)
    # EEPROM restored, then a reboot: RAM at its defaults, the backup still there.
    assert ph.read1ByteTxRx(port, 1, RETURN_DELAY) == (0, COMM_SUCCESS, 0)
    assert ph.read4ByteTxRx(port, 1, PROFILE_VELOCITY) == (0, COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 1, ADDRESS_1) == (DATA_1, COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 1, BACKUP_READY) == (1, COMM_SUCCESS, 0)

    # Startup Configuration: bit 1 restores the backed-up RAM items at boot, bit 0 turns
    # torque on.
    assert ph.write1ByteTxRx(port, 1, STARTUP, 0x03) == (COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 1, PROFILE_VELOCITY, 100) == (COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 1, ADDRESS_1, GOAL) == (COMM_SUCCESS, 0)
    assert backup_packet(ph, port, 1, STORE) == (COMM_SUCCESS, 0)
    assert ph.reboot(port, 1) == (COMM_SUCCESS, 0)
    assert ph.read4ByteTxRx(port, 1, PROFILE_VELOCITY) == (100, COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 1, ADDRESS_1) == (GOAL, COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 1, TORQUE) == (1, COMM_SUCCESS, 0)


def test_a_broadcast_backup_stores_on_every_motor_without_a_reply(
    emulator: Emulator, sdk_port: Port, ph: Any
) -> None:
    port = sdk_port(emulator((1, 2)))
    assert backup_packet(ph, port, 0xFE, STORE) == (COMM_SUCCESS, 0)
    assert ph.ping(port, 1)[1] == COMM_SUCCESS  # a barrier: the bus serves in order
    assert [ph.read1ByteTxRx(port, i, BACKUP_READY)[0] for i in (1, 2)] == [1, 1]


def test_backup_refusals(emulator: Emulator, sdk_port: Port, ph: Any) -> None:
    emu = emulator((1, 2))
    emu.motors[2].set("firmware_version", 44)
    port = sdk_port(emu)
    assert backup_packet(ph, port, 1, RESTORE) == (COMM_SUCCESS, StatusError.RESULT_FAIL)
    assert backup_packet(ph, port, 1, b"\x01CTRX") == (COMM_SUCCESS, StatusError.DATA_RANGE)
    assert backup_packet(ph, port, 1, b"\x03CTRL") == (COMM_SUCCESS, StatusError.DATA_RANGE)
    assert backup_packet(ph, port, 1, b"\x01CTR") == (COMM_SUCCESS, StatusError.DATA_LENGTH)
    assert backup_packet(ph, port, 2, STORE) == (COMM_SUCCESS, StatusError.INSTRUCTION)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (COMM_SUCCESS, 0)
    assert backup_packet(ph, port, 1, STORE) == (COMM_SUCCESS, StatusError.RESULT_FAIL)
    assert ph.read1ByteTxRx(port, 1, BACKUP_READY) == (0, COMM_SUCCESS, 0)


# -- one motor ------------------------------------------------------------------------------


@pytest.fixture
def motor(clock: ManualClock) -> EmulatedMotor:
    return EmulatedMotor(1, clock=clock)


def map_slots(motor: EmulatedMotor, first_slot: int, address: int, size: int) -> None:
    assert motor.write(first_slot, bytes(slots_for(address, size))) == StatusError.NONE


def test_one_packet_may_map_and_write_through(motor: EmulatedMotor) -> None:
    """The mapping bytes of a packet take effect for its own Indirect Data bytes."""
    mapping = [LED] + [DATA_1 + k for k in range(1, 28)]  # slot 1 → LED, the rest default
    data = bytes(byte for a in mapping for byte in le(a, 2)) + bytes([1] + [0] * 27)
    assert motor.write(ADDRESS_1, data) == StatusError.NONE
    assert motor.get("led") == 1


def test_bytes_land_where_each_slot_points(motor: EmulatedMotor) -> None:
    """Goal Position mapped in reverse byte order still receives each byte at its target."""
    reverse = [byte for a in (119, 118, 117, 116) for byte in le(a, 2)]
    assert motor.write(ADDRESS_1, bytes(reverse)) == StatusError.NONE
    assert motor.write(DATA_1, bytes([0, 0, 0x04, 0x00])) == StatusError.NONE
    assert motor.get("goal_position") == 1024
    assert motor.goals_written == [1024]


def test_a_slot_mapped_to_a_reserved_byte_reads_zero_and_refuses_writes(
    motor: EmulatedMotor,
) -> None:
    map_slots(motor, ADDRESS_1, 66, 1)  # 66-67 are reserved
    assert motor.read(DATA_1, 1) == b"\x00"
    assert motor.write(DATA_1, b"\x01") == StatusError.ACCESS


def test_the_table_matches_the_e_manual() -> None:
    assert len(INDIRECT_SLOT) == 56
    assert [BY_NAME[f"indirect_address_{n}"].address for n in (1, 28, 29, 56)] == [
        168,
        222,
        578,
        632,
    ]
    assert [BY_NAME[f"indirect_data_{n}"].address for n in (1, 28, 29, 56)] == [
        224,
        251,
        634,
        661,
    ]
    assert [BY_NAME[f"indirect_address_{n}"].default for n in (1, 28, 29, 56)] == [
        224,
        251,
        634,
        661,
    ]
    assert (BY_NAME["backup_ready"].address, BY_NAME["backup_ready"].writable) == (147, False)
    assert BY_NAME["startup_configuration"].address == 60
    assert {it.name for it in BACKUP_RAM_ITEMS} >= {"profile_velocity", "indirect_address_56"}
