"""Clocks for the emulated motors: a manual one for tests and a scaled one for demos.

A clock is any zero-argument callable returning seconds as a float that never goes
backwards; the motors read it to place their motion profiles in time. The default is
`time.monotonic`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

#: A source of time in seconds (monotonic).
Clock = Callable[[], float]


class ManualClock:
    """Virtual time (seconds) that moves only when `advance` is called.

    Thread-safe: the emulator's serving thread reads it while a test advances it.
    """

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)
        self._lock = threading.Lock()

    def __call__(self) -> float:
        with self._lock:
            return self._now

    @property
    def now(self) -> float:
        """The current virtual time (s)."""
        return self()

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
    """`time.monotonic` sped up by ``speedup`` (> 0), starting at 0 s when created."""

    def __init__(self, speedup: float = 1.0) -> None:
        if not speedup > 0:
            raise ValueError(f"speedup must be > 0, got {speedup}")
        self.speedup = float(speedup)
        self._origin = time.monotonic()

    def __call__(self) -> float:
        return (time.monotonic() - self._origin) * self.speedup
