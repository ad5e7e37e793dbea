"""The interfaces every backend implements, and the driver error hierarchy.

The acquisition engine talks to hardware only through these small protocols (in the
manner of ophyd's ``Movable`` / ``Readable``): real backends (Dynamixel over serial, a
serial detector) and simulated ones satisfy the same ones. Units: radians, seconds,
degrees Celsius, volts.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import TracebackType
from typing import Protocol, Self, runtime_checkable

# -- errors ---------------------------------------------------------------------------


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


class DetectorError(DriverError):
    """The detector did not answer, answered nonsense, or was reset mid-read."""


# -- values ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Health:
    """One motor's condition: temperature (°C), input voltage (V), named error flags."""

    temperature_c: float
    voltage_v: float
    error_flags: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.error_flags


@dataclass(frozen=True)
class Reading:
    """A detector measurement.

    ``value`` is the mean signal in the detector's units (counts), ``std`` the standard
    deviation of the ``n`` raw samples averaged (0 for one sample), ``saturated`` whether
    any sample hit the full scale, ``raw`` the individual samples.
    """

    value: float
    std: float
    n: int
    saturated: bool
    raw: tuple[float, ...] = field(default_factory=tuple)


# -- a shared shape ----------------------------------------------------------------------


class Resource:
    """Mixin: a context manager that calls ``open()`` on entry and ``close()`` on exit
    (also on an exception or Ctrl-C). Subclasses implement both; ``close`` must be safe
    to call twice and must release the device whatever state it is in."""

    def open(self) -> None:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


# -- protocols ------------------------------------------------------------------------


@runtime_checkable
class MotorBus(Protocol):
    """A set of motor axes moved together. A context manager: entering opens the
    connection (and checks the motors), leaving stops them and releases it, also on
    an exception or Ctrl-C."""

    @property
    def axes(self) -> tuple[str, ...]:
        """The axis names, in configuration order."""
        ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...

    def move_to(self, targets: Mapping[str, float]) -> None:
        """Command axis positions (radians); returns at once. Raises `LimitError`
        before anything is sent if a target is outside its axis's limits."""
        ...

    def wait_settled(self, timeout_s: float) -> None:
        """Block until every axis has stopped moving at its goal. On timeout, tell every
        axis to hold where it is and raise `MotionTimeout` (`CommError` only when the
        bus itself fails, `MotorFault` when a motor reports a hardware error)."""
        ...

    def positions(self) -> dict[str, float]:
        """Positions read back from the devices (radians)."""
        ...

    def stop(self) -> None:
        """Hold every axis where it is now (also a faulted axis's neighbours)."""
        ...

    def torque(self, on: bool) -> None:
        """Enable or disable holding torque on every axis."""
        ...

    def health(self) -> dict[str, Health]:
        """Temperature, voltage and error flags per axis."""
        ...


@runtime_checkable
class Detector(Protocol):
    """Something that measures the light reaching it."""

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose for ``exposure_s`` seconds, ``averages`` times, and return the mean."""
        ...


@runtime_checkable
class LightSource(Protocol):
    """An optional switchable source."""

    @property
    def is_on(self) -> bool: ...

    def on(self) -> None: ...

    def off(self) -> None: ...
