"""Ctrl-C and SIGTERM during a run: the first asks the run to stop after the sample in
flight (or at once, abandoning it, when it would not finish within ``grace_s``); a
second stops at once. Either way the exception is a `KeyboardInterrupt`, which every
driver already treats as Ctrl-C (axes held, port released)."""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType, TracebackType
from typing import Self


class RunInterrupted(KeyboardInterrupt):
    """The run was stopped by a signal (``signum``)."""

    def __init__(self, signum: int, *, abandoned: bool) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.abandoned = abandoned


class StopRequests:
    """Installs SIGINT and SIGTERM handlers for the length of a ``with`` block (in the
    main thread only; elsewhere it only records `request` calls).

    ``remaining_s()`` says how long the step in flight still needs (s); the engine
    keeps it current. The first signal sets `requested` when that is at most
    ``grace_s``, else raises `RunInterrupted` (abandoned); the second raises at once.
    """

    def __init__(self, remaining_s: Callable[[], float] = lambda: 0.0, grace_s: float = 5.0):
        self.remaining_s = remaining_s
        self.grace_s = grace_s
        self.signum: int | None = None
        self.armed = True
        self._previous: dict[int, object] = {}

    @property
    def requested(self) -> bool:
        return self.signum is not None

    def request(self, signum: int = signal.SIGINT) -> None:
        """What a first signal does (also callable directly, e.g. by a test). Once
        `disarm`ed, a signal is only recorded (the run is already stopping)."""
        if not self.armed:
            self.signum = self.signum or signum
            return
        if self.signum is not None:
            raise RunInterrupted(signum, abandoned=True)
        self.signum = signum
        if self.remaining_s() > self.grace_s:
            raise RunInterrupted(signum, abandoned=True)

    def raise_if_requested(self) -> None:
        """`RunInterrupted` (nothing abandoned) if a first signal asked the run to stop:
        what the engine calls where it may stop (between targets, in a pause)."""
        if self.signum is not None:
            raise RunInterrupted(self.signum or signal.SIGINT, abandoned=False)

    def disarm(self) -> None:
        """From now on signals raise nothing: the run is ending (holding the axes,
        journaling how it ended), which a second Ctrl-C must not cut short."""
        self.armed = False

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.request(signum)

    def __enter__(self) -> Self:
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                self._previous[s] = signal.signal(s, self._handler)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        for s, handler in self._previous.items():
            signal.signal(s, handler)  # type: ignore[arg-type]
        self._previous.clear()
