"""The failures of a serial detector: the error classes, which OS exceptions mean the
port failed, and how a failure to open the port is explained."""

from __future__ import annotations

import errno
import os
from typing import Literal

from drivers.errors import DetectorError, DeviceClosed

try:  # POSIX only; tcflush failures on a vanished device raise termios.error
    import termios

    IO_ERRORS: tuple[type[Exception], ...] = (OSError, termios.error)
except ImportError:  # pragma: no cover - Windows
    IO_ERRORS = (OSError,)

OPEN_ERRORS: tuple[type[Exception], ...] = (*IO_ERRORS, ValueError)  # ValueError: bad URL

ErrorKind = Literal[
    "invalid",  # a bad configuration field or measure() argument; nothing was sent
    "open",  # the port could not be opened (missing, busy, permission denied)
    "closed",  # measure() on a detector that is not open
    "timeout",  # no (complete) answer before the deadline
    "malformed",  # too many lines that do not match the expected answer
    "overflow",  # a line longer than max_line_bytes, and nothing usable after it
    "reset",  # the device printed its reset banner while the driver waited for an answer
    "device",  # the device answered with an error line
    "value",  # a well-formed answer carrying NaN, inf or a negative std
    "io",  # the operating system reported an error on the port (unplugged?)
    "streaming",  # measure() during a stream, a second start, a read with none running
]


class SerialDetectorError(DetectorError):
    """A serial detector failed. ``port`` names it, ``kind`` says what happened, and
    ``line`` is the offending line received from the device, when there is one."""

    def __init__(
        self, message: str, *, port: str, kind: ErrorKind, line: str | None = None
    ) -> None:
        super().__init__(message)
        self.port = port
        self.kind: ErrorKind = kind
        self.line = line


class SerialDetectorClosed(SerialDetectorError, DeviceClosed):
    """``measure()`` on a detector that is not open; nothing was sent."""


class SerialDetectorValueError(SerialDetectorError, ValueError):
    """An invalid configuration field or ``measure()`` argument; nothing was sent."""


_OPEN_HINTS = {
    errno.ENOENT: "no such device (not plugged in, or another name: "
    "`python -m serial.tools.list_ports` lists the ports)",
    errno.EACCES: "permission denied (on Linux add the user to the 'dialout' group "
    "and log in again)",
    errno.EPERM: "operation not permitted (on Linux add the user to the 'dialout' group)",
    errno.EBUSY: "port busy: another program has it open",
    errno.EAGAIN: "port busy: another program holds it (a serial monitor, ModemManager, "
    "another gonio run?)",
    errno.ENXIO: "device not configured (unplugged?)",
    errno.ENODEV: "no such device (unplugged?)",
    errno.EIO: "input/output error (unplugged, or a faulty cable?)",
    errno.ENOTTY: "not a serial port",
}


def open_reason(exc: BaseException) -> str:
    code = getattr(exc, "errno", None)
    if isinstance(code, int) and code in _OPEN_HINTS:
        return _OPEN_HINTS[code]
    if isinstance(code, int):
        return os.strerror(code)
    return " ".join(str(exc).split()) or type(exc).__name__
