"""How a session of a run ends: its `Outcome` and `Report`, `EndSession`, the exception
the engine's loops (`gonio.acquire.engine`, `gonio.acquire.fly.loop`) raise to end it,
and what a fault event journals of a driver error (`fault_data`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from drivers.errors import CommError, DriverError, MotorFault

Outcome = Literal["completed", "interrupted", "fault", "aborted", "paused", "journal"]


class EndSession(Exception):
    """Ends the session with ``outcome`` (raised inside the loop)."""

    def __init__(self, outcome: Outcome, message: str) -> None:
        super().__init__(message)
        self.outcome = outcome


@dataclass
class Report:
    """How a session of a run ended."""

    outcome: Outcome
    measured: int  # targets measured in this session
    skipped: int  # targets skipped in this session
    message: str = ""


def fault_data(exc: DriverError) -> dict[str, Any]:
    """What a ``fault`` or ``retry`` event journals of ``exc``: its kind and message, and
    the motor, axis, flags or port it names."""
    data: dict[str, Any] = {"error": type(exc).__name__, "message": str(exc)}
    if isinstance(exc, MotorFault):
        data.update(motor_id=exc.motor_id, axis=exc.axis, flags=list(exc.flags))
    if isinstance(exc, CommError):
        data.update(port=exc.port, motor_id=exc.motor_id)
    return data
