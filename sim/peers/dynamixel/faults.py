"""Injected bus faults and how they change the bytes a motor sends.

Reply faults are queued per motor and consumed one status packet at a time (a count
of None never runs out), or strike each status packet at random with a rate
(`FaultBook.strike`, after the queued ones); hardware alerts are not kept here, they
latch a bit in the motor's Hardware Error Status. A late reply (`Fault.LATE`) carries
its delay: the status packet, and every byte the bus sends after it, leaves that much
later, as when a loaded host or a USB adapter hands the bytes on late (they keep their
order).
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from enum import Enum

from drivers.dynamixel import HARDWARE_ERROR_BITS
from sim.peers.dynamixel.instructions import FastChain, Response, fast_chain_bytes
from sim.peers.dynamixel.motor import EmulatedMotor
from sim.peers.dynamixel.protocol import status_packet

#: Noise written before a reply by `Fault.GARBAGE` (holds no FF FF FD header).
NOISE = bytes([0xAA, 0x00, 0xFF, 0x13, 0xFD, 0x55, 0x7E])


class Fault(Enum):
    """Faults `sim.peers.dynamixel.emulator.DxlEmulator.inject` can cause."""

    NO_REPLY = "no_reply"  #: the status packet is lost
    CORRUPT_CRC = "corrupt_crc"  #: the status packet's CRC is wrong
    WRONG_ID = "wrong_id"  #: the status packet carries another ID (ID + 128 mod 253)
    GARBAGE = "garbage"  #: noise bytes arrive before the status packet
    #: the motor's previous status packet arrives again just before this one: a late
    #: reply the host had given up on (nothing extra if the motor has not answered yet)
    STALE = "stale"
    #: the status packet leaves ``delay_ms`` late, and what follows it on the bus waits
    #: behind it: past the host's timeout, it arrives in the host's next transaction
    LATE = "late"
    SILENT = "silent"  #: the whole bus is unplugged until cleared
    # Hardware alerts: latch a Hardware Error Status bit (REBOOT clears it).
    INPUT_VOLTAGE = "input_voltage"
    OVERHEATING = "overheating"
    MOTOR_ENCODER = "motor_encoder"
    ELECTRICAL_SHOCK = "electrical_shock"
    OVERLOAD = "overload"

    @property
    def alert_bit(self) -> int | None:
        """The Hardware Error Status bit of a hardware alert (None for other faults)."""
        return next((bit for bit, name in HARDWARE_ERROR_BITS.items() if name == self.value), None)


REPLY_FAULTS = frozenset(
    {Fault.NO_REPLY, Fault.CORRUPT_CRC, Fault.WRONG_ID, Fault.GARBAGE, Fault.STALE, Fault.LATE}
)


@dataclass(frozen=True)
class Outgoing:
    """The bytes a status puts on the wire after its faults, and how late (s) they leave."""

    raw: bytes
    delay_s: float = 0.0


@dataclass
class _Pending:
    fault: Fault
    remaining: int | None
    delay_s: float = 0.0


def _wrong_id(packet_id: int) -> int:
    return (packet_id + 128) % 253


def _corrupt(raw: bytes) -> bytes:
    return raw[:-2] + bytes([raw[-2] ^ 0xFF, raw[-1] ^ 0x5A])


class FaultBook:
    """The reply faults waiting for each motor. Not thread-safe: the emulator locks."""

    def __init__(self) -> None:
        self._queues: dict[EmulatedMotor, list[_Pending]] = {}
        #: Reply faults striking any status packet at random: [(fault, probability)].
        self._rates: list[tuple[Fault, float]] = []
        self._rng = random.Random(0)
        #: Each motor's last status packet as it left (clean), for `Fault.STALE`.
        self._last: dict[EmulatedMotor, bytes] = {}

    def add(
        self, motor: EmulatedMotor, fault: Fault, count: int | None, delay_s: float = 0.0
    ) -> None:
        """Queue ``fault`` for ``motor``'s next ``count`` status packets; ``delay_s`` (s)
        is how late a `Fault.LATE` reply leaves."""
        if fault not in REPLY_FAULTS:
            raise ValueError(f"{fault} is not a reply fault")
        if count is not None and count < 1:
            raise ValueError(f"count must be ≥ 1 or None, got {count}")
        if (fault is Fault.LATE) != (delay_s > 0):
            raise ValueError(f"a late reply (and only it) needs a delay > 0, got {delay_s!r} s")
        self._queues.setdefault(motor, []).append(_Pending(fault, count, delay_s))

    def strike(self, fault: Fault, rate: float, seed: int = 0) -> None:
        """Let ``fault`` strike each status packet with probability ``rate`` (on top of
        other rates; 0 ends it), drawn from a generator seeded with ``seed``."""
        if fault not in REPLY_FAULTS or fault is Fault.LATE:
            raise ValueError(f"{fault} is not a reply fault that strikes at a rate")
        if not 0.0 <= rate <= 1.0:
            raise ValueError(f"rate must be in [0, 1], got {rate}")
        self._rates = [(f, r) for f, r in self._rates if f is not fault]
        if rate > 0:
            self._rates.append((fault, rate))
        self._rng = random.Random(seed)

    def clear(self) -> None:
        self._queues.clear()
        self._rates.clear()

    def take(self, motor: EmulatedMotor) -> Fault | None:
        """The fault for ``motor``'s next status packet (consumes one count)."""
        return self._take(motor)[0]

    def _take(self, motor: EmulatedMotor) -> tuple[Fault | None, float]:
        """(fault, delay in s) for ``motor``'s next status packet (consumes one count)."""
        queue = self._queues.get(motor)
        if not queue:
            for fault, rate in self._rates:
                if self._rng.random() < rate:
                    return fault, 0.0
            return None, 0.0
        head = queue[0]
        if head.remaining is not None:
            head.remaining -= 1
            if head.remaining == 0:
                queue.pop(0)
        return head.fault, head.delay_s

    def encode(self, response: Response) -> Outgoing | None:
        """What ``response`` puts on the wire after its faults (None: nothing)."""
        if isinstance(response, FastChain):
            raw = self._encode_chain(response)
            return None if raw is None else Outgoing(raw)
        fault, delay_s = self._take(response.motor)
        if fault is Fault.NO_REPLY:
            return None
        packet_id = _wrong_id(response.packet_id) if fault is Fault.WRONG_ID else response.packet_id
        raw = status_packet(packet_id, response.error, response.params)
        stale = self._last.get(response.motor, b"") if fault is Fault.STALE else b""
        self._last[response.motor] = raw
        if fault is Fault.CORRUPT_CRC:
            raw = _corrupt(raw)
        return Outgoing(stale + (NOISE + raw if fault is Fault.GARBAGE else raw), delay_s)

    def _encode_chain(self, chain: FastChain) -> bytes | None:
        """A fast-read chain: a lost block truncates it, a wrong ID shows in its block,
        a corrupt CRC spoils the packet CRC, garbage precedes the packet (a stale or a late
        reply has no effect here)."""
        blocks: list[tuple[int, int, bytes]] = []
        noise, corrupt = b"", False
        for block in chain.blocks:
            fault = self.take(block.motor)
            if fault is Fault.NO_REPLY:
                continue
            noise = NOISE if fault is Fault.GARBAGE else noise
            corrupt = corrupt or fault is Fault.CORRUPT_CRC
            packet_id = _wrong_id(block.packet_id) if fault is Fault.WRONG_ID else block.packet_id
            blocks.append((block.error, packet_id, block.params))
        if not blocks:
            return None
        raw = fast_chain_bytes(blocks, chain.length)
        return noise + (_corrupt(raw) if corrupt else raw)
