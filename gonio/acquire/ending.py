"""How a session of a run ends: its `Outcome`, and `EndSession`, the exception the
engine's loops (`gonio.acquire.engine`, `gonio.acquire.fly.loop`) raise to end it."""

from __future__ import annotations

from typing import Literal

Outcome = Literal["completed", "interrupted", "fault", "aborted", "paused", "journal"]


class EndSession(Exception):
    """Ends the session with ``outcome`` (raised inside the loop)."""

    def __init__(self, outcome: Outcome, message: str) -> None:
        super().__init__(message)
        self.outcome = outcome
