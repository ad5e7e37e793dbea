"""Dynamixel Protocol 2.0 packets: CRC, byte stuffing, building and parsing.

Packet layout (little endian)::

    FF FF FD 00 | ID | LEN_L LEN_H | INST | PARAM ... | CRC_L CRC_H

LEN counts INST (or, in a status packet, 0x55 and the ERROR byte), the parameters
after stuffing, and the two CRC bytes. The CRC is CRC-16 with polynomial 0x8005
(x¹⁶ + x¹⁵ + x² + 1), initial value 0, no reflection, over every byte from the header
to the last parameter. Stuffing: inside INST and PARAM, each FF FF FD is followed by an
extra FD so that it cannot be mistaken for a header; the receiver removes it, and a
packet in which FF FF FD is *not* followed by FD is corrupt (`StuffingError`).

This is our own codec: the driver uses the unmodified ``dynamixel-sdk``; this module
serves the bus emulator and the tests that check the SDK's bytes.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

HEADER = b"\xff\xff\xfd\x00"
BROADCAST_ID = 0xFE
STATUS = 0x55


class Instruction(IntEnum):
    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    FACTORY_RESET = 0x06
    REBOOT = 0x08
    CLEAR = 0x10
    CONTROL_TABLE_BACKUP = 0x20
    SYNC_READ = 0x82
    SYNC_WRITE = 0x83
    FAST_SYNC_READ = 0x8A
    BULK_READ = 0x92
    BULK_WRITE = 0x93
    FAST_BULK_READ = 0x9A


class StatusError(IntEnum):
    """The error number in bits 0-6 of a status packet's ERROR byte."""

    NONE = 0
    RESULT_FAIL = 1
    INSTRUCTION = 2
    CRC = 3
    DATA_RANGE = 4
    DATA_LENGTH = 5
    DATA_LIMIT = 6
    ACCESS = 7


#: Bit 7 of the ERROR byte: the device has a hardware error (read Hardware Error Status).
ALERT = 0x80


def _crc_table() -> tuple[int, ...]:
    table = []
    for i in range(256):
        crc = i << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes) -> int:
    """CRC-16/0x8005 (init 0, not reflected) of ``data``."""
    crc = 0
    for byte in data:
        crc = ((crc << 8) ^ _CRC_TABLE[((crc >> 8) ^ byte) & 0xFF]) & 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Insert an FD after every FF FF FD in ``body`` (instruction and parameters)."""
    out = bytearray()
    for byte in body:
        out.append(byte)
        if byte == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF:
            out.append(0xFD)
    return bytes(out)


def unstuff(body: bytes) -> bytes:
    """Remove the FD that `stuff` inserted after each FF FF FD.

    ValueError if an FF FF FD is not followed by that FD (the sender did not stuff: the
    bytes cannot be trusted to mean what they seem).
    """
    out = bytearray()
    i = 0
    while i < len(body):
        out.append(body[i])
        if body[i] == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF:
            if i + 1 >= len(body) or body[i + 1] != 0xFD:
                raise ValueError(f"FF FF FD at byte {i - 2} is not followed by the stuffing FD")
            i += 1  # skip the stuffed FD
        i += 1
    return bytes(out)


def _packet(packet_id: int, body: bytes) -> bytes:
    stuffed = stuff(body)
    length = len(stuffed) + 2
    head = HEADER + bytes([packet_id, length & 0xFF, length >> 8]) + stuffed
    crc = crc16(head)
    return head + bytes([crc & 0xFF, crc >> 8])


def instruction_packet(packet_id: int, instruction: int, params: bytes = b"") -> bytes:
    """An instruction packet for ``packet_id`` (0-252, or 254 for broadcast)."""
    return _packet(packet_id, bytes([instruction]) + params)


def status_packet(packet_id: int, error: int = 0, params: bytes = b"") -> bytes:
    """A status packet from ``packet_id`` with ERROR byte ``error``."""
    return _packet(packet_id, bytes([STATUS, error]) + params)


@dataclass(frozen=True)
class Packet:
    """A parsed packet. For status packets ``instruction`` is 0x55 and ``error`` is set;
    ``params`` are unstuffed."""

    id: int
    instruction: int
    params: bytes
    error: int | None = None

    @property
    def is_status(self) -> bool:
        return self.instruction == STATUS


class CorruptPacket(ValueError):
    """A complete packet that cannot be trusted (``packet_id`` says from whom)."""

    def __init__(self, packet_id: int, reason: str) -> None:
        super().__init__(f"{reason} in a packet with ID {packet_id}")
        self.packet_id = packet_id


class CRCError(CorruptPacket):
    """A complete packet whose CRC does not match."""

    def __init__(self, packet_id: int) -> None:
        super().__init__(packet_id, "CRC mismatch")


class StuffingError(CorruptPacket):
    """A complete packet with a good CRC but an unstuffed FF FF FD in its body."""


class PacketReader:
    """Splits a byte stream into packets, resynchronizing on the header after noise.

    ``feed(data)`` appends bytes; ``next_packet()`` returns the next complete packet (or
    None) and raises `CRCError` for a complete packet with a bad CRC, `StuffingError` for
    one with an unstuffed FF FF FD (after discarding it).
    """

    #: The longest packet accepted (LEN is 16 bits, but nothing here needs more).
    MAX_LENGTH = 4096

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> None:
        self._buf += data

    def clear(self) -> None:
        self._buf.clear()

    @property
    def pending(self) -> int:
        """Bytes received but not yet part of a complete packet."""
        return len(self._buf)

    def next_packet(self) -> Packet | None:
        """The next complete packet, or None if more bytes are needed."""
        while True:
            start = self._buf.find(HEADER)
            if start < 0:
                # Keep a possible partial header at the end.
                keep = (
                    3
                    if self._buf.endswith(HEADER[:3])
                    else 2
                    if self._buf.endswith(HEADER[:2])
                    else 1
                    if self._buf.endswith(HEADER[:1])
                    else 0
                )
                del self._buf[: len(self._buf) - keep]
                return None
            del self._buf[:start]
            if len(self._buf) < 7:
                return None
            length = self._buf[5] | (self._buf[6] << 8)
            if length < 3 or length > self.MAX_LENGTH:
                del self._buf[:1]  # not a real header: resynchronize
                continue
            total = 7 + length
            if len(self._buf) < total:
                return None
            raw = bytes(self._buf[:total])
            del self._buf[:total]
            packet_id = raw[4]
            if crc16(raw[:-2]) != (raw[-2] | (raw[-1] << 8)):
                raise CRCError(packet_id)
            try:
                body = unstuff(raw[7:-2])
            except ValueError as exc:
                raise StuffingError(packet_id, str(exc)) from None
            if body[0] == STATUS:
                return Packet(packet_id, STATUS, body[2:], error=body[1] if len(body) > 1 else 0)
            return Packet(packet_id, body[0], body[1:])


def parse(data: bytes) -> Packet:
    """The single packet in ``data`` (ValueError if there is not exactly one)."""
    reader = PacketReader()
    reader.feed(data)
    packet = reader.next_packet()
    if packet is None or reader.pending:
        raise ValueError(f"not exactly one complete packet: {data.hex(' ')}")
    return packet
