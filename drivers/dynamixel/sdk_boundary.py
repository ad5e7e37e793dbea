"""Where our link meets ``dynamixel-sdk``: three corrections, applied at our boundary.

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

A late reply of exactly the expected length and ID cannot be told from the answer by
its bytes; the link drains the line after every failed or interrupted transaction so
that one cannot arrive in the next.
"""

from __future__ import annotations

from typing import Any

import dynamixel_sdk as sdk
from dynamixel_sdk import protocol2_packet_handler as p2

#: Parameters of a PING status: model number (2) and firmware version (1).
PING_PARAMS = 3


def status_params(rxpacket: list[int]) -> list[int]:
    """The parameters of an (unstuffed) status packet: LEN minus INST, ERR and CRC."""
    count = sdk.DXL_MAKEWORD(rxpacket[p2.PKT_LENGTH_L], rxpacket[p2.PKT_LENGTH_H]) - 4
    start = p2.PKT_PARAMETER0 + 1
    return list(rxpacket[start : start + max(count, 0)])


class Port(sdk.PortHandler):  # type: ignore[misc]
    """The SDK's ``PortHandler`` with its own latency timer (ms) instead of the global."""

    def __init__(self, port_name: str, latency_timer: float) -> None:
        super().__init__(port_name)
        self.latency_timer = float(latency_timer)

    def setPacketTimeout(self, packet_length: int) -> None:
        self.packet_start_time = self.getCurrentTime()
        self.packet_timeout = self.tx_time_per_byte * packet_length + self.latency_timer * 2.0 + 2.0


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
        rxpacket, result, error = super().txRxPacket(port, txpacket)
        instruction = txpacket[p2.PKT_INSTRUCTION]
        if result == sdk.COMM_SUCCESS and rxpacket is not None and instruction != sdk.INST_READ:
            expected = PING_PARAMS if instruction == sdk.INST_PING else 0
            if not error & 0x7F and len(status_params(rxpacket)) != expected:
                result = sdk.COMM_RX_CORRUPT
        return rxpacket, int(result), int(error)

    def readRx(self, port: Any, dxl_id: int, length: int) -> tuple[list[int], int, int]:
        """As the SDK's, but ``data`` is the status's parameters, however many."""
        while True:
            rxpacket, result = self.rxPacket(port, False)
            if result != sdk.COMM_SUCCESS or rxpacket[p2.PKT_ID] == dxl_id:
                break
        if result == sdk.COMM_SUCCESS:
            return status_params(rxpacket), int(result), int(rxpacket[p2.PKT_ERROR])
        return [], int(result), 0

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
