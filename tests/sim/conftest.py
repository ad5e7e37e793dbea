"""Fixtures for the simulated backend: raw links and SDK ports on emulated buses
(the `clock`, `emulator` and `latency_timer` fixtures are in tests/conftest.py)."""

from __future__ import annotations

import os
import select
import time
from collections.abc import Callable, Iterator
from typing import Any

import dynamixel_sdk as sdk
import pytest

from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.protocol import Packet, PacketReader
from sim.peers.dynamixel.tty import set_raw

#: How long (s) an exchange waits for the emulator to serve what it was sent (a late
#: reply's delay included) and for the answer to cross the pty: a bound for a loaded
#: machine, not a time spent (an exchange returns as soon as the answer is in).
SERVED_S = 2.0


class RawLink:
    """The host end of an emulated bus, byte by byte (the tty set raw at ``baud``).

    Given the emulator (``emu``), an exchange waits until the emulator has served what
    it sent and reads exactly the bytes it answered with, however long a loaded machine
    holds them (up to `SERVED_S`); without it, what comes within the call's timeout.
    """

    def __init__(self, path: str, baud: int, emu: DxlEmulator | None = None) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        self.emu = emu
        self.set_baud(baud)

    def set_baud(self, baud: int) -> None:
        set_raw(self.fd, baud)

    def send(self, data: bytes) -> None:
        os.write(self.fd, data)

    def recv(self, timeout: float = 0.2, *, until: int | None = None) -> bytes:
        """Bytes arriving within ``timeout`` s (returns early once ``until`` bytes came)."""
        out = bytearray()
        deadline = time.monotonic() + timeout
        while until is None or len(out) < until:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            ready, _, _ = select.select([self.fd], [], [], left)
            if ready:
                out += os.read(self.fd, 4096)
        return bytes(out)

    def answered(self, data: bytes) -> int | None:
        """Send ``data``; the number of bytes the emulator wrote once it had served it
        (None without the emulator, or if it had not served it within `SERVED_S`)."""
        if self.emu is None:
            self.send(data)
            return None
        heard, said = self.emu.totals()
        self.send(data)
        if not self.emu.wait_served(heard + len(data), SERVED_S):
            return None
        return self.emu.totals()[1] - said

    def transact(self, data: bytes, expect: int, timeout: float = 0.5) -> bytes:
        """Send ``data`` and return the ``expect`` bytes of the answer (fewer if the bus
        answered fewer, or on timeout)."""
        said = self.answered(data)
        if said is None:
            return self.recv(timeout, until=expect)
        return self.recv(max(timeout, SERVED_S), until=min(expect, said))

    def packets(self, data: bytes, timeout: float = 0.05) -> list[Packet]:
        """Send ``data`` and parse the answer: every byte the emulator answered with
        (without it, what comes back within ``timeout`` s)."""
        said = self.answered(data)
        reader = PacketReader()
        reader.feed(self.recv(timeout) if said is None else self.recv(SERVED_S, until=said))
        out: list[Packet] = []
        while (packet := reader.next_packet()) is not None:
            out.append(packet)
        return out

    def close(self) -> None:
        os.close(self.fd)


@pytest.fixture
def raw_link() -> Iterator[Callable[[DxlEmulator], RawLink]]:
    """Factory: a raw host link to an emulator, at the emulator's rate."""
    links: list[RawLink] = []

    def make(emu: DxlEmulator, baud: int | None = None) -> RawLink:
        link = RawLink(emu.path, baud or emu.baud, emu)
        links.append(link)
        return link

    yield make
    for link in links:
        link.close()


#: The SDK's LATENCY_TIMER (ms) for plain SDK ports on an emulator: their timeouts are
#: 2 × it + 2 ms + the reply's wire time, and a plain SDK call has no retries. A pty has
#: no adapter to wait for, so its timer only bounds how long a loaded machine may hold
#: the emulator's answer: 150 gives 302 ms (each expected timeout costs that).
SDK_LATENCY_TIMER = 150


@pytest.fixture
def sdk_port(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[DxlEmulator], Any]]:
    """Factory: an open SDK PortHandler on an emulator, at the emulator's rate (the SDK's
    LATENCY_TIMER pinned to `SDK_LATENCY_TIMER` for the test)."""
    monkeypatch.setattr(sdk.port_handler, "LATENCY_TIMER", SDK_LATENCY_TIMER)
    ports: list[Any] = []

    def make(emu: DxlEmulator, baud: int | None = None) -> Any:
        port = sdk.PortHandler(emu.path)
        assert port.openPort()
        assert port.setBaudRate(baud or emu.baud)
        ports.append(port)
        return port

    yield make
    for port in ports:
        port.closePort()


@pytest.fixture
def ph() -> Any:
    """The SDK's Protocol 2.0 packet handler."""
    return sdk.PacketHandler(2.0)
