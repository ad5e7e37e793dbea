"""`PtyHost`: one pseudo-terminal a peer serves from a daemon thread.

The host opens the pty (the slave set raw, the master non-blocking, optionally in
packet mode so that a host's flush is seen), runs the peer's serving loop on a daemon
thread, wakes it through a pipe, and on `stop` joins it and closes every descriptor.
While any peer serves, `sim.peers.responsive` keeps the interpreter's switch interval
short. The peer keeps its protocol; the host knows nothing of it.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import struct
import termios
import threading
import tty
from collections.abc import Callable

from sim.peers import responsive


def _set_raw(fd: int) -> None:
    tty.setraw(fd)  # no echo, no newline translation before a host configures it


class PtyHost:
    """A pseudo-terminal served by ``serve`` on a daemon thread named ``name``.

    ``configure(slave)`` sets the slave's line discipline when it opens (default: raw);
    ``packet_mode``: the master reads a control byte before each chunk (TIOCPKT), so a
    host's flush shows; ``hold_slave``: keep the slave open while serving (the master
    never reads EIO between hosts, but ``fuser``/``lsof`` name the server; released, the
    port looks free until a host opens it); ``join_s``: how long `stop` waits for the
    thread (s). ``serve`` returns when `stopping` is set (it watches `wake` to learn it).
    """

    def __init__(
        self,
        serve: Callable[[], None],
        name: str,
        *,
        configure: Callable[[int], object] = _set_raw,
        packet_mode: bool = False,
        hold_slave: bool = True,
        join_s: float = 5.0,
    ) -> None:
        self._serve = serve
        self._name = name
        self._configure = configure
        self._packet_mode = packet_mode and hasattr(termios, "TIOCPKT")
        self._hold_slave = hold_slave
        self._join_s = join_s
        self._master: int | None = None
        self._slave: int | None = None
        self._wake: tuple[int, int] | None = None
        self._path: str | None = None
        self._thread: threading.Thread | None = None
        #: Set by `stop`: the serving loop returns.
        self.stopping = threading.Event()

    @property
    def running(self) -> bool:
        """Whether the serving thread was started and not stopped."""
        return self._thread is not None

    @property
    def packet_mode(self) -> bool:
        """Whether the master reads in packet mode (a control byte before each chunk)."""
        return self._packet_mode

    @property
    def path(self) -> str:
        """The pty device a host opens (e.g. ``/dev/pts/3``), after `start`."""
        if self._path is None:
            raise RuntimeError(f"{self._name} is not started")
        return self._path

    @property
    def master(self) -> int:
        """The master end the peer reads and writes (after `start`)."""
        if self._master is None:
            raise RuntimeError(f"{self._name} is not started")
        return self._master

    @property
    def slave(self) -> int | None:
        """The slave end, while the host holds it (None otherwise)."""
        return self._slave

    @property
    def wake(self) -> int:
        """The pipe end the serving loop watches: readable after `wakeup` or `stop`."""
        if self._wake is None:
            raise RuntimeError(f"{self._name} is not started")
        return self._wake[0]

    def start(self) -> str:
        """Open the pty, start serving, and return the path a host opens."""
        if self._thread is not None:
            raise RuntimeError(f"{self._name} is already started")
        master, slave = os.openpty()
        try:
            self._configure(slave)
            os.set_blocking(master, False)
            if self._packet_mode:
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
        self.stopping.clear()
        self._thread = threading.Thread(target=self._serve, name=self._name, daemon=True)
        self._thread.start()
        responsive.serving_started()
        return path

    def stop(self) -> None:
        """Stop serving and close the pty (idempotent; a host still holding it sees an
        I/O error)."""
        thread, self._thread = self._thread, None
        self.stopping.set()
        if thread is not None:
            self.wakeup()
            thread.join(timeout=self._join_s)
            responsive.serving_stopped()
        for fd in (self._master, self._slave, *(self._wake or ())):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = self._wake = None

    def wakeup(self) -> None:
        """Make `wake` readable: the serving loop looks again (or sees `stopping`)."""
        if self._wake is not None:
            with contextlib.suppress(OSError):
                os.write(self._wake[1], b"!")
