"""Where our link meets ``dynamixel-sdk``: its corrections, applied at our boundary.

The SDK is installed unmodified (from PyPI); `DynamixelLink` uses these two subclasses
of its classes instead of the originals. Each override says which SDK behaviour it
replaces (checked against dynamixel-sdk 4.1.0, ``protocol2_packet_handler.py`` and
``port_handler.py``):

1. **Per-port latency timer.** ``PortHandler.setPacketTimeout`` reads the module global
   ``port_handler.LATENCY_TIMER``, shared by every port of the process: a second bus
   opened with a shorter setting would silently shrink the first one's reply timeouts.
   `Port` carries its own ``latency_timer`` (ms) and never reads or writes the global.
2. **Byte stuffing on send.** ``Protocol2PacketHandler.txPacket`` calls
   ``addStuffing(txpacket)`` and ignores the result; when stuffing lengthens the packet
   ``addStuffing`` builds and returns a *new* list, so an instruction whose parameters
   contain FF FF FD (Homing Offset or an extended-mode goal of −131073, bytes
   FF FF FD FF) goes out unstuffed and a motor sees a header in the middle of it.
   `PacketHandler.txPacket` sends what ``addStuffing`` returns. (Receiving is right:
   ``rxPacket`` unstuffs status packets.)
3. **Reply lengths.** ``readRx``/``readTxRx`` slice ``length`` bytes after the error
   byte whatever the status packet holds: a status with fewer parameters (a refused
   read, or a late reply to another instruction) yields fewer bytes, the CRC taken as
   data, or nothing, which the ``readNByte`` helpers decode as 0; a longer one is cut to
   size. Ours return exactly the status's parameters (its LEN minus instruction, error
   and CRC), so the caller can compare with the length it asked for (the link retries a
   mismatch as a corrupt packet). PING and the instructions whose status carries no data
   (WRITE, REBOOT, …) check the count here and report a mismatch as ``COMM_RX_CORRUPT``.

4. **Whose reply.** ``txRxPacket`` and ``readRx`` skip status packets of other IDs
   until one of the expected ID comes: a late reply of another motor is silently
   passed over and one of the same motor taken. Ours read exactly one status packet
   (the SDK's ``rxPacket`` already insists on the status instruction 0x55 and a valid
   CRC) and report ``COMM_RX_CORRUPT`` when its ID is not the request's, when its
   parameters are not as many as the request asks (`reply_params`), or when more bytes
   are waiting after it: a reply the bus still owed to an earlier transaction. The
   link's sync reads check every expected ID exactly once, in order, the same way.

5. **Waiting for a reply.** ``rxPacket`` calls ``readPort`` in a loop until the packet
   is complete or its timeout has passed, and ``readPort`` reads what is there without
   waiting (the port's timeout is 0): the loop spins for the whole reply time, a core
   busy and, in Python, the interpreter's lock held, so a peer in the same process
   (an emulator's thread, a UI) is starved of the very time it needs to answer. `Port`'s
   ``readPort`` first waits until a byte is there or the packet's time is up (`select`,
   which lets the other threads run) and then reads what is there, as the SDK's would:
   the same bytes at the same moments, the same timeouts.

A late reply of exactly the expected length and ID cannot be told from the answer by
its bytes. The link therefore never starts a transaction while the bus may still owe
a reply: after a failed or interrupted one it first *syncs* (`Syncer`): a READ whose
reply length nothing outstanding has, every status before its answer discarded —
bytes keep their order on the bus, so nothing owed can come after it.
"""

from __future__ import annotations

import select
from typing import Any

import dynamixel_sdk as sdk
from dynamixel_sdk import protocol2_packet_handler as p2

#: Parameters of a PING status: model number (2) and firmware version (1).
PING_PARAMS = 3
#: Bytes of a status packet besides its parameters: header 4, ID, LEN 2, INST, ERR, CRC 2.
STATUS_OVERHEAD = 11


def status_params(rxpacket: list[int]) -> list[int]:
    """The parameters of an (unstuffed) status packet: LEN minus INST, ERR and CRC."""
    count = sdk.DXL_MAKEWORD(rxpacket[p2.PKT_LENGTH_L], rxpacket[p2.PKT_LENGTH_H]) - 4
    start = p2.PKT_PARAMETER0 + 1
    return list(rxpacket[start : start + max(count, 0)])


def reply_params(txpacket: list[int]) -> int:
    """The parameters the status to instruction ``txpacket`` carries when the motor
    carries it out: a READ's length, a PING's 3, none for the others (WRITE, REBOOT, …)."""
    instruction = txpacket[p2.PKT_INSTRUCTION]
    if instruction == sdk.INST_READ:
        start = p2.PKT_PARAMETER0 + 2
        return int(sdk.DXL_MAKEWORD(txpacket[start], txpacket[start + 1]))
    return PING_PARAMS if instruction == sdk.INST_PING else 0


def answers(rxpacket: list[int], dxl_id: int, params: int) -> bool:
    """Whether status ``rxpacket`` can be the answer of motor ``dxl_id`` to a request
    whose reply carries ``params`` parameters: its ID, and its parameter count unless
    it reports an error number (a refused instruction carries none)."""
    if rxpacket[p2.PKT_ID] != dxl_id:
        return False
    return bool(rxpacket[p2.PKT_ERROR] & 0x7F) or len(status_params(rxpacket)) == params


class Port(sdk.PortHandler):  # type: ignore[misc]
    """The SDK's ``PortHandler`` with its own latency timer (ms) instead of the global."""

    def __init__(self, port_name: str, latency_timer: float) -> None:
        super().__init__(port_name)
        self.latency_timer = float(latency_timer)

    def setPacketTimeout(self, packet_length: int) -> None:
        self.packet_start_time = self.getCurrentTime()
        self.packet_timeout = self.tx_time_per_byte * packet_length + self.latency_timer * 2.0 + 2.0

    def readPort(self, length: int) -> bytes:
        """Up to ``length`` bytes: what is there once a byte is, or once the present
        packet's time is up (nothing waits past it)."""
        left_ms = self.packet_timeout - self.getTimeSinceStart()
        if length > 0 and left_ms > 0 and not self.ser.in_waiting:
            select.select([self.ser.fileno()], [], [], left_ms / 1000.0)
        return bytes(self.ser.read(length))


class PacketHandler(p2.Protocol2PacketHandler):  # type: ignore[misc]
    """The SDK's Protocol 2.0 packet handler, stuffing what it sends and reporting the
    true length of what it receives."""

    def txPacket(self, port: Any, txpacket: list[int]) -> int:
        if port.is_using:
            return int(sdk.COMM_PORT_BUSY)
        port.is_using = True
        packet = self.addStuffing(txpacket)  # a new, longer list when stuffing was needed
        total = sdk.DXL_MAKEWORD(packet[p2.PKT_LENGTH_L], packet[p2.PKT_LENGTH_H]) + 7
        if total > p2.TXPACKET_MAX_LEN:
            port.is_using = False
            return int(sdk.COMM_TX_ERROR)
        packet[p2.PKT_HEADER0 : p2.PKT_RESERVED + 1] = [0xFF, 0xFF, 0xFD, 0x00]
        crc = self.updateCRC(0, packet, total - 2)
        packet[total - 2] = sdk.DXL_LOBYTE(crc)
        packet[total - 1] = sdk.DXL_HIBYTE(crc)
        port.clearPort()
        if port.writePort(packet[:total]) != total:
            port.is_using = False
            return int(sdk.COMM_TX_FAIL)
        return int(sdk.COMM_SUCCESS)

    def txRxPacket(self, port: Any, txpacket: list[int]) -> tuple[Any, int, int]:
        """Send ``txpacket`` and read its one status packet: ``COMM_RX_CORRUPT`` if that
        is not the answer (`answers`) or more bytes wait behind it."""
        result = self.txPacket(port, txpacket)
        instruction = txpacket[p2.PKT_INSTRUCTION]
        if result != sdk.COMM_SUCCESS:
            return None, int(result), 0
        if instruction in (sdk.INST_SYNC_READ, sdk.INST_BULK_READ):
            port.is_using = False  # their statuses are read by the group classes
            return None, int(sdk.COMM_NOT_AVAILABLE), 0
        if txpacket[p2.PKT_ID] == sdk.BROADCAST_ID or instruction == sdk.INST_ACTION:
            port.is_using = False  # no status comes back
            return None, int(result), 0
        params = reply_params(txpacket)
        port.setPacketTimeout(params + STATUS_OVERHEAD)
        rxpacket, result = self.rxPacket(port, False)
        if result != sdk.COMM_SUCCESS:
            return rxpacket, int(result), 0
        error = int(rxpacket[p2.PKT_ERROR])
        if not answers(rxpacket, txpacket[p2.PKT_ID], params) or port.getBytesAvailable():
            return rxpacket, int(sdk.COMM_RX_CORRUPT), error
        return rxpacket, int(result), error

    def readRx(self, port: Any, dxl_id: int, length: int) -> tuple[list[int], int, int]:
        """The next status packet, as motor ``dxl_id``'s answer of ``length`` bytes: its
        parameters, however many; ``COMM_RX_CORRUPT`` if it is another motor's or of
        another length (a refused read's error aside)."""
        rxpacket, result = self.rxPacket(port, False)
        if result != sdk.COMM_SUCCESS:
            return [], int(result), 0
        error = int(rxpacket[p2.PKT_ERROR])
        if not answers(rxpacket, dxl_id, length):
            return [], int(sdk.COMM_RX_CORRUPT), error
        return status_params(rxpacket), int(result), error

    def readTxRx(
        self, port: Any, dxl_id: int, address: int, length: int
    ) -> tuple[list[int], int, int]:
        """As the SDK's, but ``data`` is the status's parameters, however many."""
        if dxl_id >= sdk.BROADCAST_ID:
            return [], int(sdk.COMM_NOT_AVAILABLE), 0
        txpacket = [0] * 14
        txpacket[p2.PKT_ID] = dxl_id
        txpacket[p2.PKT_LENGTH_L] = 7
        txpacket[p2.PKT_LENGTH_H] = 0
        txpacket[p2.PKT_INSTRUCTION] = sdk.INST_READ
        txpacket[p2.PKT_PARAMETER0 : p2.PKT_PARAMETER0 + 4] = [
            sdk.DXL_LOBYTE(address),
            sdk.DXL_HIBYTE(address),
            sdk.DXL_LOBYTE(length),
            sdk.DXL_HIBYTE(length),
        ]
        rxpacket, result, error = self.txRxPacket(port, txpacket)
        if result != sdk.COMM_SUCCESS:
            return [], int(result), int(error)
        return status_params(rxpacket), int(result), int(rxpacket[p2.PKT_ERROR])


class SyncRead(sdk.GroupSyncRead):  # type: ignore[misc]
    """The SDK's GroupSyncRead, keeping each status packet's error byte (the SDK drops it,
    and with it the alert bit), taking the statuses one each from the expected motors
    in order, refusing one of another motor or whose data is not ``data_length`` bytes,
    or more bytes waiting after the last (a late reply to another instruction) as
    corrupt, and naming the motor that did not answer or answered wrong."""

    errors: dict[int, int]
    failed: int | None = None

    def read(self) -> int:
        self.errors = {}
        self.failed = None
        result = self.txPacket()
        if result != sdk.COMM_SUCCESS:
            return int(result)
        for motor_id in self.data_dict:
            data, result, error = self.ph.readRx(self.port, motor_id, self.data_length)
            if result == sdk.COMM_SUCCESS and not error & 0x7F and len(data) != self.data_length:
                result = sdk.COMM_RX_CORRUPT
            if result != sdk.COMM_SUCCESS:
                self.failed = motor_id
                return int(result)
            self.data_dict[motor_id] = data
            self.errors[motor_id] = error
        if self.port.getBytesAvailable():  # a status more than the motors asked owed
            return int(sdk.COMM_RX_CORRUPT)
        self.last_result = True
        return int(sdk.COMM_SUCCESS)
