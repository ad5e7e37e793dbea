"""What a bus of X-series motors does with one instruction packet: pure logic, no I/O.

`handle` executes a parsed `Packet` on the motors that hear it and returns the status
packets they send, in bus order, as `Reply` records (who, what, at which baud and
return delay) for the emulator to encode, delay and write. Rules (ROBOTIS e-manual):

* PING is always answered; a broadcast PING by every motor in ID order.
* Status Return Level 0 answers only PING, 1 also the read family (READ, SYNC_READ,
  BULK_READ and their fast forms), 2 everything.
* A broadcast instruction gets no status, except PING and the sync/bulk reads.
* An instruction sent to a motor's Secondary ID is executed without a status, and may
  not write EEPROM.
* Unknown instruction → Instruction error (2); wrong parameter count → Data Length
  error (5); ACTION without REG_WRITE → Instruction error.
* The reply leaves with the ID, baud rate and return delay the motor had when the
  packet arrived, so a write to ID or Baud Rate takes effect after its status.
* CONTROL_TABLE_BACKUP (0x20, firmware ≥ 45): option 1 + "CTRL" stores the backup and
  answers; option 2 + "CTRL" answers, then restores the EEPROM area and reboots. Torque
  on → Result Fail (the refusals are `EmulatedMotor.check_backup`).
* Reads and writes reach Indirect Data like any address (sync and bulk forms included);
  the motor resolves the indirection.
* FAST_SYNC_READ / FAST_BULK_READ: one status packet with ID 0xFE whose parameters are,
  per motor, ERR, ID, DATA and a CRC of the packet so far (the last one is the packet
  CRC); LEN counts the whole requested chain, so a missing motor truncates it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from sim.peers.dynamixel.backup import BACKUP_RESTORE, BACKUP_STORE
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import (
    BROADCAST_ID,
    HEADER,
    STATUS,
    Instruction,
    Packet,
    StatusError,
    crc16,
)

#: The magic parameters of CLEAR option 1 (reset the multi-turn count).
CLEAR_MULTI_TURN = bytes([0x01, 0x44, 0x58, 0x4C, 0x22])

_READS = {
    Instruction.READ,
    Instruction.SYNC_READ,
    Instruction.BULK_READ,
    Instruction.FAST_SYNC_READ,
    Instruction.FAST_BULK_READ,
}


@dataclass(frozen=True)
class Reply:
    """One status packet (or one motor's block of a fast-read chain)."""

    motor: EmulatedMotor
    packet_id: int
    error: int
    params: bytes
    baud: int
    delay: float  # Return Delay Time (s)


@dataclass(frozen=True)
class FastChain:
    """The combined status of a FAST_SYNC_READ / FAST_BULK_READ."""

    blocks: tuple[Reply, ...]
    length: int  # LEN field of the whole chain as requested


Response = Reply | FastChain


def fast_chain_bytes(blocks: Sequence[tuple[int, int, bytes]], length: int) -> bytes:
    """The wire bytes of a fast-read chain of (error, id, data) blocks (not stuffed)."""
    out = bytearray(HEADER + bytes([BROADCAST_ID, length & 0xFF, length >> 8, STATUS]))
    for error, motor_id, data in blocks:
        out += bytes([error, motor_id]) + data
        crc = crc16(bytes(out))
        out += bytes([crc & 0xFF, crc >> 8])
    return bytes(out)


def _u16(data: bytes, offset: int) -> int:
    return data[offset] | (data[offset + 1] << 8)


def _reply(motor: EmulatedMotor, error: int = 0, params: bytes = b"") -> Reply:
    return Reply(motor, motor.id, motor.status_error(error), params, motor.baud, motor.return_delay)


def _answers(motor: EmulatedMotor, instruction: int) -> bool:
    if instruction == Instruction.PING:
        return True
    level = motor.status_return_level
    return level >= 2 or (level == 1 and instruction in _READS)


def _read(motor: EmulatedMotor, address: int, length: int) -> tuple[int, bytes]:
    if length < 1:
        return StatusError.DATA_LENGTH, b""
    if address + length > motor.table.size:
        return StatusError.ACCESS, b""
    return StatusError.NONE, motor.read(address, length)


def handle(packet: Packet, motors: Sequence[EmulatedMotor]) -> list[Response]:
    """Execute ``packet`` on the ``motors`` that hear it; the status packets they send."""
    if packet.is_status:
        return []
    if packet.id == BROADCAST_ID:
        return _broadcast(packet, motors)
    primary = [m for m in motors if m.id == packet.id]
    shadow = [m for m in motors if m.id != packet.id and m.secondary_id == packet.id]
    out: list[Response] = []
    for motor in primary + shadow:
        # The status leaves with the ID, baud and delay the motor had on arrival.
        before = _reply(motor)
        answers = motor in primary and _answers(motor, packet.instruction)
        error, params = _unicast(packet, motor, via_secondary=motor not in primary)
        if answers:
            out.append(replace(before, error=motor.status_error(error), params=params))
        _after_effects(packet, motor)
    return out


def _unicast(packet: Packet, motor: EmulatedMotor, *, via_secondary: bool) -> tuple[int, bytes]:
    inst, p = packet.instruction, packet.params
    lengths: dict[int, int] = {
        Instruction.PING: 0,
        Instruction.READ: 4,
        Instruction.ACTION: 0,
        Instruction.REBOOT: 0,
        Instruction.FACTORY_RESET: 1,
        Instruction.CLEAR: 5,
    }
    if inst in lengths and len(p) != lengths[inst]:
        return StatusError.DATA_LENGTH, b""
    if inst in (Instruction.WRITE, Instruction.REG_WRITE) and len(p) < 3:
        return StatusError.DATA_LENGTH, b""
    if inst == Instruction.PING:
        return StatusError.NONE, motor.model.to_bytes(2, "little") + bytes([motor.firmware])
    if inst == Instruction.READ:
        return _read(motor, _u16(p, 0), _u16(p, 2))
    if inst == Instruction.WRITE:
        return motor.write(_u16(p, 0), p[2:], via_secondary=via_secondary), b""
    if inst == Instruction.REG_WRITE:
        return motor.reg_write(_u16(p, 0), p[2:]), b""
    if inst == Instruction.ACTION:
        return motor.action(), b""
    if inst == Instruction.REBOOT:
        return StatusError.NONE, b""  # the reboot itself follows the status
    if inst == Instruction.FACTORY_RESET:
        valid = p[0] in (0x01, 0x02, 0xFF)
        return (StatusError.NONE if valid else StatusError.DATA_RANGE), b""
    if inst == Instruction.CLEAR:
        if p != CLEAR_MULTI_TURN:
            return StatusError.DATA_RANGE, b""
        return motor.clear_multi_turn(), b""
    if inst == Instruction.CONTROL_TABLE_BACKUP:
        error = motor.check_backup(p)
        if not error and p[0] == BACKUP_STORE:
            motor.store_backup()
        return error, b""
    return StatusError.INSTRUCTION, b""


def _after_effects(packet: Packet, motor: EmulatedMotor) -> None:
    """REBOOT, FACTORY_RESET and a backup restore act after the motor has answered."""
    if packet.instruction == Instruction.CONTROL_TABLE_BACKUP:
        p = packet.params
        if p and p[0] == BACKUP_RESTORE and not motor.check_backup(p):
            motor.restore_backup()
    elif packet.instruction == Instruction.REBOOT and not packet.params:
        motor.reboot()
    elif packet.instruction == Instruction.FACTORY_RESET and len(packet.params) == 1:
        option = packet.params[0]
        if packet.id == BROADCAST_ID and option == 0xFF:
            return  # e-manual: a broadcast "reset all" is not executed (firmware ≥ 42)
        motor.factory_reset(option)


def _broadcast(packet: Packet, motors: Sequence[EmulatedMotor]) -> list[Response]:
    inst, p = packet.instruction, packet.params
    by_id = {m.id: m for m in motors}
    if inst == Instruction.PING:
        ordered = sorted(motors, key=lambda m: m.id)
        return [_reply(m, *_unicast(packet, m, via_secondary=False)) for m in ordered]
    if inst in (Instruction.SYNC_READ, Instruction.FAST_SYNC_READ):
        if len(p) < 5:
            return []
        address, length = _u16(p, 0), _u16(p, 2)
        requests = [(i, address, length) for i in p[4:]]
        return _read_many(requests, by_id, inst == Instruction.FAST_SYNC_READ)
    if inst in (Instruction.BULK_READ, Instruction.FAST_BULK_READ):
        if not p or len(p) % 5:
            return []
        requests = [(p[i], _u16(p, i + 1), _u16(p, i + 3)) for i in range(0, len(p), 5)]
        return _read_many(requests, by_id, inst == Instruction.FAST_BULK_READ)
    if inst == Instruction.SYNC_WRITE:
        _apply_writes(_sync_writes(p), by_id)
    elif inst == Instruction.BULK_WRITE:
        _apply_writes(_bulk_writes(p), by_id)
    elif inst in (
        Instruction.WRITE,
        Instruction.REG_WRITE,
        Instruction.ACTION,
        Instruction.CLEAR,
        Instruction.CONTROL_TABLE_BACKUP,
    ):
        for motor in motors:
            error, _ = _unicast(packet, motor, via_secondary=False)
            if not error:
                _after_effects(packet, motor)
    elif inst in (Instruction.REBOOT, Instruction.FACTORY_RESET):
        for motor in motors:
            _after_effects(packet, motor)
    return []


def _read_many(
    requests: list[tuple[int, int, int]], by_id: dict[int, EmulatedMotor], fast: bool
) -> list[Response]:
    """Each listed motor's answer in list order (each ID once; absent motors are silent)."""
    replies: list[Reply] = []
    seen: set[int] = set()
    for motor_id, address, length in requests:
        motor = by_id.get(motor_id)
        if motor_id in seen or motor is None:
            continue
        seen.add(motor_id)
        if not _answers(motor, Instruction.SYNC_READ):
            continue
        error, data = _read(motor, address, length)
        if fast and error:
            data = bytes(length)
        replies.append(_reply(motor, error, data))
    if not fast:
        return list(replies)
    if not replies:
        return []
    length = 1 + sum(4 + n for _, _, n in requests)
    return [FastChain(tuple(replies), length)]


def _sync_writes(p: bytes) -> list[tuple[int, int, bytes]]:
    if len(p) < 5:
        return []
    address, length = _u16(p, 0), _u16(p, 2)
    body = p[4:]
    if length < 1 or len(body) % (1 + length):
        return []
    step = 1 + length
    return [(body[i], address, body[i + 1 : i + step]) for i in range(0, len(body), step)]


def _bulk_writes(p: bytes) -> list[tuple[int, int, bytes]]:
    writes: list[tuple[int, int, bytes]] = []
    i = 0
    while i < len(p):
        if i + 5 > len(p):
            return []
        length = _u16(p, i + 3)
        if i + 5 + length > len(p):
            return []
        writes.append((p[i], _u16(p, i + 1), p[i + 5 : i + 5 + length]))
        i += 5 + length
    return writes


def _apply_writes(writes: list[tuple[int, int, bytes]], by_id: dict[int, EmulatedMotor]) -> None:
    for motor_id, address, data in writes:
        motor = by_id.get(motor_id)
        if motor is not None:
            motor.write(address, data)


def instruction_name(code: int) -> str:
    """``Instruction`` name of ``code``, or its hex value if unknown."""
    try:
        return Instruction(code).name
    except ValueError:
        return f"0x{code:02X}"
