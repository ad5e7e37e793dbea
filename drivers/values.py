"""The values the device contract's calls return (`drivers.base`): a motor's `Health`,
what a recovery did (`Recovered`), a detector's `Reading` and `RangeChange`, and one poll
of moving axes (`StampedPositions`). Units: radians, seconds, degrees Celsius, volts;
detector values in the detector's units.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Health:
    """One motor's condition: temperature (°C), input voltage (V), named error flags
    and load (% of the motor's maximum, signed; None where the backend does not
    measure it)."""

    temperature_c: float
    voltage_v: float
    error_flags: tuple[str, ...] = ()
    load_pct: float | None = None

    @property
    def ok(self) -> bool:
        return not self.error_flags


@dataclass(frozen=True)
class Recovered:
    """What `MotorBus.recover` did to ``axis``: ``held_rad``, the position it was told to
    hold just before its motor was rebooted, and ``position_rad``, the one read back
    after (rad)."""

    axis: str
    held_rad: float
    position_rad: float


@dataclass(frozen=True)
class Reading:
    """A detector measurement.

    ``value`` is the mean signal in the detector's units (counts), ``std`` the standard
    deviation of the ``n`` raw samples averaged (0 for one sample), ``saturated`` whether
    any sample hit the full scale, ``started_s`` / ``ended_s`` the clock's time (s) when
    the first exposure began and the last one ended (readout included), ``raw`` the
    individual samples, ``exposure_s`` the exposure actually integrated (s) when the
    device's step made it differ from the one asked (e.g. whole milliseconds), else None,
    ``phase_deg`` a lock-in's mean phase (°) over the samples, else None.
    """

    value: float
    std: float
    n: int
    saturated: bool
    started_s: float
    ended_s: float
    raw: tuple[float, ...] = field(default_factory=tuple)
    exposure_s: float | None = None
    phase_deg: float | None = None

    @property
    def middle_s(self) -> float:
        """The middle of the measurement (s): where a drifting source is sampled."""
        return 0.5 * (self.started_s + self.ended_s)


@dataclass(frozen=True)
class RangeChange:
    """The instrument's range changed (auto-ranging): when (the clock's s), from, to
    (in the reading's unit)."""

    at_s: float
    old: float | None
    new: float


@dataclass(frozen=True)
class StampedPositions:
    """One poll of the axes while they may move: ``positions`` (rad, per axis) read in
    one transaction, ``request_s`` the clock's time (s) just before the request was sent
    and ``reply_s`` just after the last reply arrived; the positions were sampled in
    between. ``arrived`` is True when every axis is within its position tolerance of its
    last goal (the sweep's motion is over; ``wait_settled`` confirms it)."""

    positions: dict[str, float]
    request_s: float
    reply_s: float
    arrived: bool = False

    @property
    def middle_s(self) -> float:
        """The middle of the poll's window (s): the best single time for its positions."""
        return 0.5 * (self.request_s + self.reply_s)

    @property
    def window_s(self) -> float:
        """How long the poll took (s): its timing uncertainty is at most this."""
        return self.reply_s - self.request_s
