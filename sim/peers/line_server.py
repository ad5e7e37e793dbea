"""`LineServer`: a line-based peer's transport on a pseudo-terminal (the simulated
photometer, the lamp relay, the VISA instruments each hold one).

It holds a `PtyHost` and serves it: reads the host's bytes into command lines and hands
each to the peer's ``on_line``, keeps the peer's scheduled answers and timed events in
one heap and writes the answers when they are due (after the link's latency). The peer's
state and the server's share one lock, `lock`."""

from __future__ import annotations

import heapq
import itertools
import os
import select
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Self

from sim.peers.pty_host import PtyHost

_MAX_LINE = 256  # longest command the device accepts
_MAX_OUT = 1 << 20  # bytes queued for the host at most; more are dropped
_TIOCPKT_FLUSHREAD = 0x01  # the slave flushed its input: pyserial does so when it opens
_TOO_LONG = b"ERR line too long\r\n"


@dataclass(order=True)
class Event:
    """What is due at ``due`` (time.monotonic() s): bytes to send, a reset, or a tick of
    a stream's window (``tick`` ≥ 0, its generation; ``middle``: the window's middle)."""

    due: float
    seq: int
    data: bytes = field(compare=False, default=b"")
    reset: bool = field(compare=False, default=False)
    tick: int = field(compare=False, default=-1)  # ≥ 0: a stream's window (its generation)
    middle: bool = field(compare=False, default=False)  # the window's middle, not its end
    linked: bool = field(compare=False, default=False)  # output already delayed by the link


class LineServer:
    """Serve a line-based peer on a pseudo-terminal.

    ``on_line(line, now)`` answers a command line (called without the lock; ``now`` in
    time.monotonic() s); ``on_reset(now, banner_now=...)`` reboots the peer (called with
    the lock held: a scheduled reset, or a host opening the port when ``reset_on_open``);
    ``on_tick(event)`` handles a stream's due window (lock held). ``hold_slave``: see
    `PtyHost`. ``name`` names the serving thread.
    """

    def __init__(
        self,
        name: str,
        on_line: Callable[[str, float], None],
        on_reset: Callable[..., None],
        on_tick: Callable[[Event], None] | None = None,
        *,
        reset_on_open: bool = False,
        hold_slave: bool = True,
    ) -> None:
        self._on_line = on_line
        self._on_reset = on_reset
        self._on_tick = on_tick
        self._reset_on_open = reset_on_open
        self.lock = threading.Lock()
        self.events: list[Event] = []
        self._seq = itertools.count()
        self._inbuf = bytearray()
        self._skipping = False  # inside a command line that was too long
        self._outbuf = bytearray()
        #: Every byte sent reaches the host this much later (s).
        self.link_latency_s = 0.0
        #: An unexpected exception that stopped serving or a defect of the peer, if any.
        self.error: BaseException | None = None
        self._pty = PtyHost(self._serve, name, packet_mode=True, hold_slave=hold_slave)

    # -- life cycle ---------------------------------------------------------------

    @property
    def path(self) -> str:
        """The pty device a host opens (e.g. ``/dev/pts/3``)."""
        return self._pty.path

    def start(self) -> str:
        """Open the pty, start serving, and return the path a host opens (already
        serving: its path)."""
        return self._pty.path if self._pty.running else self._pty.start()

    def stop(self) -> None:
        """Stop serving and close the pty (a host still holding it sees an I/O error)."""
        self._pty.stop()

    # -- what the peer schedules ------------------------------------------------------

    def schedule(self, due: float, data: bytes = b"", *, reset: bool = False) -> None:
        """Send ``data`` (or reset the peer) at ``due``."""
        with self.lock:
            self.schedule_locked(due, data, reset=reset)
        self.wakeup()

    def schedule_locked(self, due: float, data: bytes = b"", *, reset: bool = False) -> None:
        """`schedule`, the lock held (the serving loop looks at it when next woken)."""
        heapq.heappush(self.events, Event(due, next(self._seq), data, reset))

    def tick_locked(self, due: float, generation: int, *, middle: bool = False) -> None:
        """Call ``on_tick`` at ``due`` for the stream of ``generation`` (lock held)."""
        heapq.heappush(self.events, Event(due, next(self._seq), tick=generation, middle=middle))

    def output_locked(self, data: bytes, *, linked: bool = False) -> None:
        """Send ``data`` now (after the link's latency; the lock held)."""
        if self.link_latency_s and not linked and data:
            due = time.monotonic() + self.link_latency_s
            heapq.heappush(self.events, Event(due, next(self._seq), data, linked=True))
            return
        room = _MAX_OUT - len(self._outbuf)
        self._outbuf += data[: max(room, 0)]

    def wakeup(self) -> None:
        """Let the serving loop look at what was scheduled."""
        self._pty.wakeup()

    # -- the serving thread -------------------------------------------------------------

    def _serve(self) -> None:
        master, wake = self._pty.master, self._pty.wake
        try:
            while not self._pty.stopping.is_set():
                with self.lock:
                    timeout = (
                        max(0.0, self.events[0].due - time.monotonic()) if self.events else None
                    )
                    want_write = bool(self._outbuf)
                readable, writable, _ = select.select(
                    [master, wake], [master] if want_write else [], [], timeout
                )
                if wake in readable:
                    os.read(wake, 4096)
                if master in readable:
                    self._receive(master)
                if master in writable:
                    self._transmit(master)
                self._fire_due_events()
        except Exception as exc:  # pragma: no cover - reported through .error
            if not self._pty.stopping.is_set():
                self.error = exc

    def _receive(self, master: int) -> None:
        try:
            packet = os.read(master, 4096)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:  # EIO: no host has the slave open (never while the server holds it)
            time.sleep(0.01)
            return
        if not packet:
            return
        if self._pty.packet_mode:  # packet mode: a control byte, then data
            control, packet = packet[0], packet[1:]
            if control & _TIOCPKT_FLUSHREAD and self._reset_on_open:
                with self.lock:
                    self._on_reset(time.monotonic())
        now = time.monotonic()
        for byte in packet:
            if byte in b"\r\n":
                line = self._inbuf.decode("ascii", "replace").strip()
                self._inbuf.clear()
                if line and not self._skipping:
                    self._on_line(line, now)
                self._skipping = False
            elif self._skipping:
                continue
            elif len(self._inbuf) < _MAX_LINE:
                self._inbuf.append(byte)
            else:  # refuse the line and ignore the rest of it
                self._inbuf.clear()
                self._skipping = True
                self.schedule(now, _TOO_LONG)

    def _transmit(self, master: int) -> None:
        with self.lock:
            chunk = bytes(self._outbuf[:4096])
        try:
            written = os.write(master, chunk)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:  # EIO: no host has the slave open; what it was owed is dropped
            written = len(chunk)
        with self.lock:
            del self._outbuf[:written]

    def _fire_due_events(self) -> None:
        now = time.monotonic()
        with self.lock:
            while self.events and self.events[0].due <= now:
                event = heapq.heappop(self.events)
                if event.reset:
                    self._on_reset(now, banner_now=True)
                elif event.tick >= 0 and self._on_tick is not None:
                    self._on_tick(event)
                else:
                    self.output_locked(event.data, linked=event.linked)


class ServedPeer:
    """A peer served on a pty by the `LineServer` it owns: the life cycle every line
    peer (photometer, lamp relay, VISA instrument) offers its users."""

    def __init__(self, server: LineServer) -> None:
        self._server = server

    @property
    def path(self) -> str:
        """The pty device a host opens (e.g. ``/dev/pts/3``)."""
        return self._server.path

    def start(self) -> str:
        """Open the pty, start serving, and return the path a host opens."""
        return self._server.start()

    def stop(self) -> None:
        """Stop serving and close the pty (a host still holding it sees an I/O error)."""
        self._server.stop()

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.stop()

    @property
    def error(self) -> BaseException | None:
        """An unexpected exception that stopped the serving thread, if any."""
        return self._server.error
