"""The faults a test injects into the simulated photometer, and the line a pending one
sends instead of an answer or a stream line."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from sim.peers.serial_photometer.protocol import MALFORMED_LINE, _line


@dataclass
class Faults:
    """Pending faults: ``malformed`` answers, ``silent`` (ignore every command),
    ``reset_next`` (reboot mid-measurement), ``slow_s`` (s added to every answer),
    ``garbage`` (digits without a line ending), ``inject`` (lines sent verbatim) and
    ``late`` (s each next answer is late by)."""

    malformed: int = 0
    silent: bool = False
    reset_next: bool = False
    slow_s: float = 0.0
    garbage: int = 0
    inject: deque[str] = field(default_factory=deque)
    late: deque[float] = field(default_factory=deque)

    def line(self) -> bytes | None:
        """The line an injected fault sends instead of the next answer or stream line
        (garbage, an injected line, a malformed one; each used once), or None."""
        if self.garbage:
            data = (b"0123456789" * (self.garbage // 10 + 1))[: self.garbage]
            self.garbage = 0
            return data
        if self.inject:
            return _line(self.inject.popleft())
        if self.malformed:
            self.malformed -= 1
            return _line(MALFORMED_LINE)
        return None
