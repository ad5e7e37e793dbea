"""The line rate of a (pseudo-)terminal, read and set through termios.

A pty has no wire, but Linux keeps the rate the host set with ``tcsetattr`` (as
pyserial does) and reports it on either end. Standard rates up to 4 Mbit/s have a
``Bxxx`` constant; other rates (4.5 Mbit/s) go through the Linux ``termios2`` ioctls
with ``BOTHER``, which also report the exact rate of any setting.
"""

from __future__ import annotations

import fcntl
import struct
import sys
import termios
import tty

_STANDARD_RATES = (
    9600,
    19200,
    38400,
    57600,
    115200,
    230400,
    460800,
    500000,
    576000,
    921600,
    1_000_000,
    1_152_000,
    1_500_000,
    2_000_000,
    2_500_000,
    3_000_000,
    3_500_000,
    4_000_000,
)
_TERMIOS_RATES = {
    getattr(termios, f"B{rate}"): rate for rate in _STANDARD_RATES if hasattr(termios, f"B{rate}")
}
# Linux struct termios2: 4 flag words, c_line, 19 control chars, c_ispeed, c_ospeed.
_TERMIOS2 = struct.Struct("4IB19B2I")
_TCGETS2 = 0x80000000 | (_TERMIOS2.size << 16) | (ord("T") << 8) | 0x2A
_TCSETS2 = 0x40000000 | (_TERMIOS2.size << 16) | (ord("T") << 8) | 0x2B
_BOTHER = 0o010000
_LINUX = sys.platform.startswith("linux")


def tty_rate(fd: int) -> int | None:
    """The output rate (bits/s) set on the terminal ``fd`` (None if unknown)."""
    if _LINUX:
        try:
            buf = bytearray(_TERMIOS2.size)
            fcntl.ioctl(fd, _TCGETS2, buf, True)
            return int(_TERMIOS2.unpack(bytes(buf))[-1])
        except OSError:
            pass
    try:
        return _TERMIOS_RATES.get(termios.tcgetattr(fd)[5])
    except termios.error:
        return None


def set_raw(fd: int, rate: int) -> bool:
    """Make ``fd`` a raw terminal at ``rate`` bits/s (False if the rate cannot be set)."""
    tty.setraw(fd)
    code = next((c for c, r in _TERMIOS_RATES.items() if r == rate), None)
    if code is not None:
        attrs = termios.tcgetattr(fd)
        attrs[4] = attrs[5] = code
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        return True
    if not _LINUX:
        return False
    try:
        buf = bytearray(_TERMIOS2.size)
        fcntl.ioctl(fd, _TCGETS2, buf, True)
        fields = list(_TERMIOS2.unpack(bytes(buf)))
        fields[2] = (fields[2] & ~termios.CBAUD) | _BOTHER
        fields[-2] = fields[-1] = rate
        fcntl.ioctl(fd, _TCSETS2, _TERMIOS2.pack(*fields))
        return True
    except OSError:
        return False
