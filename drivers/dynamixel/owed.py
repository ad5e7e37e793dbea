"""Replies the bus may still owe, and the sync that settles them (`DynamixelLink`).

A status packet can miss the SDK's timeout (a loaded host, a USB adapter holding the
bytes) and arrive later, in the next transaction. Protocol 2.0 has no sequence
number: a late reply with the ID and length of the next request is indistinguishable
from its answer (a Current Limit read back as the bytes of another 2-byte item). So
the link never starts a transaction while a reply may be owed: every attempt that
did not end with its answer leaves its replies' parameter counts here, and the next
attempt first *syncs*: one READ from address 0 (Model Number on, every Protocol 2.0
model has it) of a length no owed reply has, every status before its answer
discarded. Bytes keep their order on the bus, so once that answer is in, nothing owed
can still come; a sync that times out is itself owed, and the next one reads another
length.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import dynamixel_sdk as sdk
from dynamixel_sdk import protocol2_packet_handler as p2

from drivers.dynamixel.sdk_boundary import STATUS_OVERHEAD, answers

#: The shortest sync READ (bytes from address 0); longer ones while this length is owed.
SYNC_FIRST_LENGTH = 5
#: How much longer than its own reply's timeout a sync waits (ms): what a late reply
#: may still need (a host stalled, an adapter's buffer); it returns at its answer.
SYNC_WAIT_MS = 100.0


@dataclass
class LateCounts:
    """What the link did about late replies: ``syncs`` made, ``discarded`` status
    packets (or corrupt ones) a sync passed over, ``failed`` syncs (no answer came)."""

    syncs: int = 0
    discarded: int = 0
    failed: int = 0


class OwedReplies:
    """The parameter counts of the status packets the bus may still send (a multiset:
    one entry per reply), and the sync that clears them."""

    def __init__(self) -> None:
        self._owed: list[int] = []
        self.counts = LateCounts()

    def __bool__(self) -> bool:
        return bool(self._owed)

    def owe(self, params: Iterable[int]) -> None:
        """Replies of these parameter counts may come (an attempt about to start)."""
        self._owed.extend(params)

    def clear(self) -> None:
        """Nothing is owed: an attempt ended with its answer, or a sync with its own."""
        self._owed.clear()

    def sync_length(self) -> int:
        """A READ length no owed reply has (so none can pass for the sync's answer)."""
        return next(n for n in itertools.count(SYNC_FIRST_LENGTH) if n not in self._owed)

    def sync(self, port: Any, packets: Any, motor_id: int, baud: int) -> int:
        """Settle the bus through ``motor_id`` (any motor that answers: the bus keeps
        order). The SDK's result: success once the sync's answer came (nothing is owed
        any more); else a timeout, or a corrupt packet if something else came (then
        the sync is owed too)."""
        self.counts.syncs += 1
        length = self.sync_length()
        txpacket = [0] * 14
        txpacket[p2.PKT_ID] = motor_id
        txpacket[p2.PKT_LENGTH_L] = 7
        txpacket[p2.PKT_INSTRUCTION] = sdk.INST_READ
        txpacket[p2.PKT_PARAMETER0 : p2.PKT_PARAMETER0 + 4] = [0, 0, length, 0]
        self.owe((length,))
        result = packets.txPacket(port, txpacket)
        if result != sdk.COMM_SUCCESS:
            port.is_using = False
            self.counts.failed += 1
            return int(result)
        wire = sum(n + STATUS_OVERHEAD for n in self._owed) * 10_000.0 / baud  # ms
        port.setPacketTimeoutMillis(wire + 2.0 * port.latency_timer + 2.0 + SYNC_WAIT_MS)
        passed = 0
        while True:
            rxpacket, result = packets.rxPacket(port, False)
            ok = result == sdk.COMM_SUCCESS and not rxpacket[p2.PKT_ERROR] & 0x7F
            if ok and answers(rxpacket, motor_id, length):
                self.counts.discarded += passed
                self.clear()
                return int(sdk.COMM_SUCCESS)
            if result == sdk.COMM_RX_TIMEOUT or port.isPacketTimeout():
                self.counts.discarded += passed
                self.counts.failed += 1
                return int(sdk.COMM_RX_CORRUPT if passed else sdk.COMM_RX_TIMEOUT)
            passed += 1
