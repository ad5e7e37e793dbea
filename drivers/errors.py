"""The errors every driver raises on purpose, under one base, `DriverError`.

Which call raises which is part of the device contract (`drivers.base`).
"""

from __future__ import annotations


class DriverError(Exception):
    """Base of every error a driver raises on purpose."""


class CommError(DriverError):
    """Communication failed: timeout, corrupt packet, port busy or missing.

    ``port``, ``motor_id`` and ``result`` (the SDK's COMM_* code, when there is one) say
    where; the message is one line a user can act on.
    """

    def __init__(
        self,
        message: str,
        *,
        port: str | None = None,
        motor_id: int | None = None,
        result: int | None = None,
    ) -> None:
        super().__init__(message)
        self.port = port
        self.motor_id = motor_id
        self.result = result


class MotorFault(DriverError):
    """A motor reported a hardware error (its Hardware Error Status, decoded)."""

    def __init__(self, message: str, *, motor_id: int, axis: str | None, flags: tuple[str, ...]):
        super().__init__(message)
        self.motor_id = motor_id
        self.axis = axis
        self.flags = flags


class MotionTimeout(DriverError):
    """Axes did not settle at their goals in time (blocked, overloaded, or too slow);
    the bus has already told them to hold where they are."""


class LimitError(DriverError):
    """A command outside an axis's configured limits; nothing was sent."""


class TorqueOff(DriverError):
    """A move was commanded with torque off; nothing was sent."""


class DeviceClosed(DriverError):
    """The device is not open (or was closed); nothing was sent."""


class DetectorError(DriverError):
    """The detector did not answer, answered nonsense, or was reset mid-read."""


class StreamNotSupported(DetectorError):
    """The detector cannot stream readings (no streaming mode, or none configured)."""


class LightError(DriverError):
    """The light source did not acknowledge a switch, or cannot be switched."""


#: The errors that mean axes may have been moving when they were raised.
MOTION_FAULTS = (MotorFault, MotionTimeout, CommError)
