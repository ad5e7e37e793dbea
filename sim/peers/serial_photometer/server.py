"""The simulated photometer's pseudo-terminal: opening and closing it, and the serving
thread that reads command lines, hands them to the device and delivers its scheduled
answers (the transport half of :class:`~sim.peers.serial_photometer.device.SerialPhotometer`)."""

from __future__ import annotations

import contextlib
import fcntl
import heapq
import itertools
import os
import select
import struct
import termios
import threading
import time
import tty
from dataclasses import dataclass, field
from types import TracebackType
from typing import TYPE_CHECKING, Self

from sim.peers import responsive
from sim.peers.serial_photometer.protocol import _line

_MAX_LINE = 256  # longest command the device accepts
_MAX_OUT = 1 << 20  # bytes queued for the host at most; more are dropped
_TIOCPKT_FLUSHREAD = 0x01  # the slave flushed its input: pyserial does so when it opens


@dataclass(order=True)
class _Event:
    due: float
    seq: int
    data: bytes = field(compare=False, default=b"")
    reset: bool = field(compare=False, default=False)
    tick: int = field(compare=False, default=-1)  # ≥ 0: a stream's window (its generation)
    middle: bool = field(compare=False, default=False)  # the window's middle, not its end
    linked: bool = field(compare=False, default=False)  # output already delayed by the link


class _PtyServer:
    """A mixin holding :class:`SerialPhotometer`'s pty life cycle and serving thread.

    Its state is created by ``SerialPhotometer.__init__``; the attributes and methods it
    uses from there are declared here.
    """

    _reset_on_open: bool
    _lock: threading.Lock
    _events: list[_Event]
    _seq: itertools.count[int]
    _inbuf: bytearray
    _skipping: bool
    _outbuf: bytearray
    _master: int | None
    _slave: int | None
    _wake: tuple[int, int] | None
    _thread: threading.Thread | None
    _stopping: threading.Event
    _path: str | None
    _error: BaseException | None
    _link_latency_s: float
    #: Whether the server keeps the pty's slave end open while it serves. Held, the
    #: master never reads EIO between hosts, but tools that look for a port's users
    #: (``fuser``, ``lsof``) name the server; released (Linux: the master then reads
    #: EIO until a host opens the slave, and the server polls every 10 ms meanwhile),
    #: the port looks free until a host opens it.
    _hold_slave: bool = True

    if TYPE_CHECKING:

        def _handle(self, line: str, now: float) -> None: ...

        def _reset_locked(self, now: float, *, banner_now: bool = False) -> None: ...

        def _tick_locked(self, event: _Event) -> None: ...

    def _init_pty_state(self) -> None:
        """The transport's state, before `start` (called by the device's ``__init__``)."""
        self._lock = threading.Lock()
        self._events = []
        self._seq = itertools.count()
        self._inbuf = bytearray()
        self._skipping = False  # inside a command line that was too long
        self._outbuf = bytearray()
        self._master = None
        self._slave = None
        self._wake = None
        self._thread = None
        self._stopping = threading.Event()
        self._path = None
        self._error = None
        self._link_latency_s = 0.0  # every byte sent reaches the host this much later (s)

    # -- life cycle ---------------------------------------------------------------

    @property
    def path(self) -> str:
        """The pty device a host opens (e.g. ``/dev/pts/3``)."""
        if self._path is None:
            raise RuntimeError("the photometer is not started")
        return self._path

    def start(self) -> str:
        """Open the pty, start serving, and return the path a host opens."""
        if self._thread is not None:
            return self.path
        master, slave = os.openpty()
        try:
            tty.setraw(slave)  # no echo, no newline translation before a host configures it
            os.set_blocking(master, False)
            if hasattr(termios, "TIOCPKT"):
                fcntl.ioctl(master, termios.TIOCPKT, struct.pack("i", 1))
            path = os.ttyname(slave)
            wake = os.pipe()
        except BaseException:
            os.close(master)
            os.close(slave)
            raise
        held: int | None = slave
        if not self._hold_slave:
            os.close(slave)
            held = None
        self._master, self._slave, self._wake, self._path = master, held, wake, path
        self._stopping.clear()
        self._thread = threading.Thread(target=self._serve, name=f"photometer {path}", daemon=True)
        self._thread.start()
        responsive.serving_started()
        return path

    def stop(self) -> None:
        """Stop serving and close the pty (a host still holding it sees an I/O error)."""
        thread, self._thread = self._thread, None
        if thread is None:
            return
        self._stopping.set()
        self._wakeup()
        thread.join(timeout=5.0)
        responsive.serving_stopped()
        for fd in (self._master, self._slave, *(self._wake or ())):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = self._wake = None

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    @property
    def error(self) -> BaseException | None:
        """An unexpected exception that stopped the serving thread, if any."""
        return self._error

    # -- the serving thread -------------------------------------------------------------

    def _serve(self) -> None:
        assert self._master is not None and self._wake is not None
        master, wake = self._master, self._wake[0]
        try:
            while not self._stopping.is_set():
                with self._lock:
                    timeout = (
                        max(0.0, self._events[0].due - time.monotonic()) if self._events else None
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
            if not self._stopping.is_set():
                self._error = exc

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
        if hasattr(termios, "TIOCPKT"):  # packet mode: a control byte, then data
            control, packet = packet[0], packet[1:]
            if control & _TIOCPKT_FLUSHREAD and self._reset_on_open:
                with self._lock:
                    self._reset_locked(time.monotonic())
        now = time.monotonic()
        for byte in packet:
            if byte in b"\r\n":
                line = self._inbuf.decode("ascii", "replace").strip()
                self._inbuf.clear()
                if line and not self._skipping:
                    self._handle(line, now)
                self._skipping = False
            elif self._skipping:
                continue
            elif len(self._inbuf) < _MAX_LINE:
                self._inbuf.append(byte)
            else:  # refuse the line and ignore the rest of it
                self._inbuf.clear()
                self._skipping = True
                self._schedule(now, _line("ERR line too long"))

    def _transmit(self, master: int) -> None:
        with self._lock:
            chunk = bytes(self._outbuf[:4096])
        try:
            written = os.write(master, chunk)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:  # EIO: no host has the slave open; what it was owed is dropped
            written = len(chunk)
        with self._lock:
            del self._outbuf[:written]

    def _fire_due_events(self) -> None:
        now = time.monotonic()
        with self._lock:
            while self._events and self._events[0].due <= now:
                event = heapq.heappop(self._events)
                if event.reset:
                    self._reset_locked(now, banner_now=True)
                elif event.tick >= 0:
                    self._tick_locked(event)
                else:
                    self._output_locked(event.data, linked=event.linked)

    def _output_locked(self, data: bytes, *, linked: bool = False) -> None:
        if self._link_latency_s and not linked and data:
            due = time.monotonic() + self._link_latency_s
            heapq.heappush(self._events, _Event(due, next(self._seq), data, linked=True))
            return
        room = _MAX_OUT - len(self._outbuf)
        self._outbuf += data[: max(room, 0)]

    def _schedule(self, due: float, data: bytes = b"", *, reset: bool = False) -> None:
        with self._lock:
            heapq.heappush(self._events, _Event(due, next(self._seq), data, reset))
        self._wakeup()

    def _schedule_locked(self, due: float, data: bytes = b"", *, reset: bool = False) -> None:
        heapq.heappush(self._events, _Event(due, next(self._seq), data, reset))

    def _wakeup(self) -> None:
        if self._wake is not None:
            with contextlib.suppress(OSError):
                os.write(self._wake[1], b"!")
