"""The emulated bus's shared half-duplex line: when each status packet would have
finished crossing it (10 bits a byte at its sender's rate, after the host packet and
anything still on the wire, plus each motor's Return Delay Time; a late reply holds the
line), and its bytes written to the pty's master then."""

from __future__ import annotations

import os
import select
import threading
import time
from collections.abc import Callable, Sequence

from sim.peers.dynamixel.faults import FaultBook
from sim.peers.dynamixel.instructions import FastChain, Reply, Response
from sim.peers.dynamixel.traffic import Traffic
from sim.peers.pty_host import PtyHost

#: Bits on the wire per byte: start, 8 data, stop.
BITS_PER_BYTE = 10


class Line:
    """The line of a bus served on ``pty``: its replies pass through ``faults`` (under
    ``lock``) and are counted in ``traffic``; ``host_baud`` gives the host's tty rate
    (None before a host opens it), ``baud`` the rate assumed without one."""

    def __init__(
        self,
        pty: PtyHost,
        lock: threading.RLock,
        faults: FaultBook,
        traffic: Traffic,
        baud: int,
        host_baud: Callable[[], int | None],
    ) -> None:
        self._pty = pty
        self._lock = lock
        self._faults = faults
        self._traffic = traffic
        self._baud = baud
        self._host_baud = host_baud
        #: perf_counter time at which the emulated line is free again (wire time on).
        self._free = 0.0

    def transmit(
        self,
        responses: Sequence[Response],
        arrived: float,
        size_in: int,
        *,
        wire_time: bool,
        return_delay: bool,
    ) -> None:
        """Write each response when it would have finished crossing the wire (at once
        without ``wire_time``; ``return_delay``: after each motor's Return Delay Time).

        A host packet of ``size_in`` bytes that arrived (perf_counter s) while earlier
        bytes (host packets without replies, or replies) would still be on the wire
        starts after them.
        """
        if not wire_time:
            due = arrived
        else:
            baud = _sender(responses[0]).baud if responses else (self._host_baud() or self._baud)
            due = max(arrived, self._free) + size_in * BITS_PER_BYTE / baud
        self._free = due
        stopping = self._pty.stopping
        for response in responses:
            sender = _sender(response)
            with self._lock:
                out = self._faults.encode(response)
            due += sender.delay if return_delay else 0.0
            if out is None:
                continue
            raw = out.raw
            due += len(raw) * BITS_PER_BYTE / sender.baud if wire_time else 0.0
            due += out.delay_s  # a late reply holds the line: nothing is served meanwhile
            self._free = due
            wait = due - time.perf_counter()
            if wait > 0 and stopping.wait(wait):
                return
            if out.delay_s:
                overtaken = bool(select.select([self._pty.master], [], [], 0)[0])
                self._traffic.late(overtaken)
            self._write(raw)

    def _write(self, raw: bytes) -> None:
        self._traffic.said(raw)
        view, master = memoryview(raw), self._pty.master
        deadline = time.monotonic() + 1.0
        while view and not self._pty.stopping.is_set() and time.monotonic() < deadline:
            try:
                view = view[os.write(master, view) :]
            except BlockingIOError:  # the host is not reading: wait, then give up
                select.select([], [master], [], 0.05)


def _sender(response: Response) -> Reply:
    """The reply whose baud and return delay time ``response`` (a chain: its first block)."""
    return response.blocks[0] if isinstance(response, FastChain) else response
