"""The simulator's clocks: virtual time for simulated runs and tests, and real time sped
up for rehearsals. Both implement `drivers.base.Clock` (``now()``, ``sleep(s)``) and are
also plain callables returning seconds, the form the emulated motors read.

A `TimeSource` is any zero-argument callable returning seconds as a float that never goes
backwards; the emulated motors read one to place their motion profiles in time (default
`time.monotonic`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

#: A source of time in seconds (monotonic), as the emulated motors read it.
TimeSource = Callable[[], float]


class ManualClock:
    """Virtual time (seconds) that moves only when `sleep` / `advance` is called: a
    simulated run reports the hours the real rig would take in the seconds it computes.

    Thread-safe: the emulator's serving thread reads it while a test advances it.
    """

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)
        self._lock = threading.Lock()

    def __call__(self) -> float:
        with self._lock:
            return self._now

    def now(self) -> float:
        """The current virtual time (s)."""
        return self()

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` (≥ 0) pass: the time moves on at once."""
        self.advance(seconds)

    def advance(self, seconds: float) -> float:
        """Move time forward by ``seconds`` (≥ 0) and return the new time."""
        if seconds < 0:
            raise ValueError(f"a clock cannot go backwards (advance by {seconds} s)")
        with self._lock:
            self._now += float(seconds)
            return self._now

    def advance_to(self, t: float) -> float:
        """Set the time to ``t`` (not before now) exactly, and return it."""
        with self._lock:
            if t < self._now:
                raise ValueError(f"a clock cannot go backwards (from {self._now} s to {t} s)")
            self._now = float(t)
            return self._now


class ScaledClock:
    """`time.monotonic` sped up by ``speedup`` (> 0), starting at 0 s when created;
    ``sleep(s)`` sleeps s / speedup real seconds."""

    def __init__(self, speedup: float = 1.0) -> None:
        if not speedup > 0:
            raise ValueError(f"speedup must be > 0, got {speedup}")
        self.speedup = float(speedup)
        self._origin = time.monotonic()

    def __call__(self) -> float:
        return self.at(time.monotonic())

    def at(self, monotonic_s: float) -> float:
        """This clock's time (s) at a `time.monotonic` time: one mapping for every peer
        that schedules in real time."""
        return (monotonic_s - self._origin) * self.speedup

    def now(self) -> float:
        return self()

    def sleep(self, seconds: float) -> None:
        if seconds < 0:
            raise ValueError(f"cannot sleep a negative time ({seconds} s)")
        time.sleep(seconds / self.speedup)
