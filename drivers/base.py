"""The device contract every backend implements: its protocols and their rules.

The acquisition engine talks to an instrument only through the small protocols here
(in the manner of ophyd's ``Movable`` / ``Readable``): `MotorBus`, `Detector`,
`LightSource` and `Clock`. The real backends (`drivers.dynamixel.bus.DynamixelBus`,
`drivers.serial_detector.detector.SerialDetector`,
`drivers.light.serial_switch.SerialLightSwitch`) and the simulated ones (`sim.virtual.devices`)
follow the same rules, and one contract suite (``tests/drivers/contract/``) runs every
rule against every backend. Units: radians, seconds, degrees Celsius, volts; detector
values in the detector's counts. The values the calls return are in `drivers.values`,
the errors they raise in `drivers.errors`, the lifecycle mixin and one run's `Devices` in
`drivers.devices`, the checks of a sweep's profile in `drivers.sweep`, streamed set-points in
`drivers.trajectory`.

The rules, in one place
-----------------------
Lifecycle (all devices)
    A device is a context manager: entering calls ``open()``, leaving calls ``close()``
    (also on an exception or Ctrl-C). ``open()`` on an open device does nothing.
    ``close()`` is idempotent, never raises for a device that is already closed, and
    releases the port whatever state the device is in; a motor bus tells every axis to
    hold before it releases its port. On a closed device every other call raises
    `DeviceClosed` and sends nothing.

Motion (`MotorBus`)
    * ``move_to`` checks every target against its axis's configured limits first: one
      target outside them (or not finite) raises `LimitError`, an unknown axis
      `DriverError`, and nothing is sent. With torque off it raises `TorqueOff` and
      nothing is sent. It returns as soon as the goals are sent.
    * ``wait_settled(timeout_s)`` returns once every axis has stopped moving at its goal
      (within the backend's position tolerance). It does **not** wait the rig's
      mechanical settle dwell (``settle_s`` in the rig file): the caller does, with
      ``Clock.sleep``, and the planner's predicted time counts the dwell exactly once
      per target, after the move.
    * Any fault raised while axes may move — `MotorFault`, `MotionTimeout`,
      `CommError` from ``move_to``, ``wait_settled`` or ``positions`` — leaves every
      answering axis already told to hold at its present position before it
      propagates: code that catches the fault inside the ``with`` block never leaves
      the healthy arms running. If an axis could not be told to hold, the exception
      says so in a note.
    * ``stop()`` holds every axis that answers at its present position, clamped to its
      limits, also right after a fault (a faulted motor's alert never prevents holding
      its neighbours); it raises `CommError` naming the axes it could not reach, and
      never raises `MotorFault`.
    * ``positions()`` are read back from the devices (encoders), never the goals.

Recovery (`MotorBus`)
    * ``health()`` reads each motor's temperature, input voltage, latched hardware
      error flags and, where the backend measures it, its load, without raising on a
      motor's alert.
    * ``recover(axis)`` first holds every answering axis where it is (as ``stop``),
      then reboots only that axis's motor (clearing its latched Hardware Error Status),
      restores the configuration ``open`` gave it (operating mode, position limits,
      profile, torque on) and leaves it holding where it is. It returns `Recovered`:
      the position (rad) the axis was told to hold just before the reboot and the one
      read back after it; comparing them is the caller's. A motor whose error is still
      there after the reboot (its cause persists: heat, load, supply) raises
      `MotorFault`, one that does not answer again `CommError`, an unknown axis
      `DriverError`; the other axes are never rebooted.

Sweeps (`MotorBus`, for measuring while moving)
    * ``sweep(targets, velocities, accelerations)`` is ``move_to`` with a velocity
      profile chosen for this move: each named axis runs a trapezoidal profile at its
      given velocity (rad/s) and acceleration (rad/s²; default its configured one) to
      its target, and returns at once with the velocities actually commanded (the
      device's register step). The checks of ``move_to`` come first and send nothing
      (a target outside the limits, an unknown axis, torque off); so does a velocity
      or acceleration that is not finite, not positive, or above the axis's configured
      one (``velocity_limits()``), as `LimitError`. The profile lasts for that move
      only: the next ``move_to`` runs the configured profile again.
    * ``poll_positions()`` reads every axis's position once (one transaction on a
      bus: a SYNC_READ) and returns `StampedPositions`: the positions (rad) and the
      clock's time just before the request left (``request_s``) and just after the
      reply arrived (``reply_s``), ``request_s`` ≤ ``reply_s`` ≤ the next poll's
      ``request_s``. The positions were sampled somewhere in that window, so an axis
      moving at v rad/s is known to v · (``reply_s`` − ``request_s``) plus one encoder
      tick. Polling never commands anything; it may be called while axes move, and a
      fault it meets holds every answering axis before it propagates (as ``positions``).
    * Polled positions are monotone along a sweep's path, and a sweep ends, like any
      move, with ``wait_settled``.

Trajectories (`MotorBus`, coordinated multi-axis motion; `drivers.trajectory`)
    * ``follow(trajectory, on_poll)`` streams a `Trajectory`'s set-points: one write of
      every axis's goal per period, interleaved with one ``poll_positions`` per period,
      each axis's profile set so that it follows without stopping (on the X series a
      new goal re-plans the profile from the present velocity). The axes must be at
      rest at set-point 0 (the caller moves there with ``move_to`` and
      ``wait_settled``): otherwise `DriverError` and nothing is sent. The whole
      trajectory is checked first (`drivers.trajectory.check_trajectory`: limits,
      velocity, acceleration, unknown axes) and with torque off `TorqueOff` is raised:
      nothing is sent.
    * ``on_poll`` (optional) is called with each poll as soon as it is made (a caller
      reads its detector's stream there); an exception it raises holds every axis and
      propagates.
    * It returns a `Followed` once the last set-point is reached (as ``wait_settled``):
      the trajectory's origin on the clock, when each set-point was sent, the polls,
      and the tracking error (the largest distance of a poll from the path at the
      poll's middle), which stays within the backend's stated bound.
    * A fault on the way (`MotorFault`, `MotionTimeout`, `CommError`) holds every
      answering axis before it propagates, as for ``move_to``.

Measuring (`Detector`)
    ``measure(exposure_s, averages)`` exposes ``averages`` times and returns one
    `Reading` stamped with the clock's time at the start and the end of the exposures.
    An exposure outside the detector's range or ``averages`` < 1 raises
    `DetectorError` before anything is exposed. A saturated reading is returned, not
    raised: ``Reading.saturated`` says so.

What a detector may also say (optional; read through the functions named, which give
the default when a detector does not say it)
    * ``dark_subtracted`` (`dark_subtracted`; default False): its readings carry no dark
      or ambient signal (a lock-in amplifier behind a chopped source), so a calibration
      takes no dark reading. Readable when closed; constant for the device's life.
    * ``unit`` (`reading_unit`; default ``"counts"``): the unit of ``Reading.value``.
    * ``phase_tolerance_deg`` (`phase_tolerance_deg`; default None): a lock-in's
      readings carry ``Reading.phase_deg``, and a drift of it from the reference
      reading's phase beyond this tolerance (°) is worth an event.
    * ``range_changes`` (`range_changes`; default none): the `RangeChange` list of an
      auto-ranging instrument, appended to while measuring, in time order.
    * ``can_stream`` (`can_stream`; default False): it offers the `StreamingDetector`
      methods. `streaming` returns such a detector or raises `StreamNotSupported`.

Streaming (`StreamingDetector`, optional): `drivers.stream`.

Light (`LightSource`)
    ``on()`` / ``off()`` switch the source and return once it is switched; ``is_on``
    is the state last commanded and acknowledged.

Time (`Clock`)
    ``now()`` is seconds on a monotonic clock; ``sleep(s)`` lets ``s`` seconds pass on
    that clock. `SystemClock` is real time; the simulator's clocks are virtual
    (`sim.clock`). Every backend built for one run shares one clock.

Simulation only (`Simulated`)
    What only a simulation has — which sample's random streams the next move and
    reading use, whether the stage shows the sample or the reference standard, the
    true joint angles, snapshots for resume — sits behind the optional `Simulated`
    protocol. The engine uses it only when a backend offers it (the run's
    ``drivers.devices.Devices.simulation``), never by poking attributes.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from types import TracebackType
from typing import TYPE_CHECKING, Any, Literal, Protocol, Self

from drivers.values import Health, RangeChange, Reading, Recovered, StampedPositions

if TYPE_CHECKING:  # numpy arrays: kept out of `gonio --help`'s imports
    from drivers.trajectory import Followed, Trajectory

# -- time -------------------------------------------------------------------------------


class Clock(Protocol):
    """Seconds on a monotonic clock, and a way to let time pass on it."""

    def now(self) -> float:
        """The time (s); never goes backwards."""
        ...

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` (≥ 0) pass on this clock."""
        ...


class SystemClock:
    """Real time: `time.monotonic` and `time.sleep`."""

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        if seconds < 0:
            raise ValueError(f"cannot sleep a negative time ({seconds} s)")
        time.sleep(seconds)


# -- protocols ------------------------------------------------------------------------


class Device(Protocol):
    """The lifecycle every device shares (see the module docstring)."""

    @property
    def is_open(self) -> bool: ...

    def open(self) -> None: ...

    def close(self) -> None: ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...


class MotorBus(Device, Protocol):
    """A set of motor axes moved together (rules: the module docstring)."""

    @property
    def axes(self) -> tuple[str, ...]:
        """The axis names, in configuration order."""
        ...

    def limits(self) -> dict[str, tuple[float, float]]:
        """Each axis's configured range (rad), inclusive."""
        ...

    def move_to(self, targets: Mapping[str, float]) -> None:
        """Send goals (rad) for the named axes; returns at once. `LimitError` or
        `TorqueOff` before anything is sent."""
        ...

    def wait_settled(self, timeout_s: float) -> None:
        """Block until every axis has stopped at its goal (not the settle dwell). On
        timeout every axis is held and `MotionTimeout` raised; `MotorFault` and
        `CommError` also hold every answering axis before they propagate."""
        ...

    def positions(self) -> dict[str, float]:
        """Positions read back from the devices (rad)."""
        ...

    def velocity_limits(self) -> dict[str, float]:
        """Each axis's configured profile velocity (rad/s): the fastest a sweep may ask."""
        ...

    def sweep(
        self,
        targets: Mapping[str, float],
        velocities: Mapping[str, float],
        accelerations: Mapping[str, float] | None = None,
    ) -> dict[str, float]:
        """Start a move of the named axes to ``targets`` (rad) at ``velocities`` (rad/s)
        with ``accelerations`` (rad/s²; default the configured ones), for this move only;
        returns at once with the velocities commanded (rad/s). `LimitError`, `TorqueOff`
        or `DriverError` before anything is sent (the module docstring)."""
        ...

    def follow(
        self,
        trajectory: Trajectory,
        on_poll: Callable[[StampedPositions], None] | None = None,
    ) -> Followed:
        """Stream ``trajectory``'s set-points (one write and one poll per period), from
        rest at set-point 0 to rest at the last; `LimitError`, `TorqueOff` or
        `DriverError` before anything is sent (the module docstring)."""
        ...

    def poll_positions(self) -> StampedPositions:
        """Positions (rad) in one transaction, stamped at request and reply (s); safe
        while moving. A fault holds every answering axis before it propagates."""
        ...

    def stop(self) -> None:
        """Hold every answering axis where it is now (`CommError` names any not held)."""
        ...

    def torque(self, on: bool) -> None:
        """Enable (holding the present position) or disable torque on every axis."""
        ...

    def health(self) -> dict[str, Health]:
        """Temperature, voltage, error flags and load per axis."""
        ...

    def recover(self, axis: str) -> Recovered:
        """Hold every axis, reboot ``axis``'s motor, restore its configuration and hold it;
        where it was held before and read after (the module docstring). `MotorFault`
        if its error persists, `CommError` if it does not answer again."""
        ...


class Detector(Device, Protocol):
    """Something that measures the light reaching it."""

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        """The shortest and longest exposure (s) it accepts."""
        ...

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose for ``exposure_s`` seconds, ``averages`` times, and return the mean."""
        ...


def dark_subtracted(detector: Detector) -> bool:
    """Whether ``detector``'s readings carry no dark or ambient signal (its optional
    ``dark_subtracted`` property; False when it has none): a calibration then takes no
    dark reading and needs no switchable light."""
    return getattr(detector, "dark_subtracted", False) is True


def reading_unit(detector: Detector) -> str:
    """The unit of ``detector``'s readings (its optional ``unit``; ``"counts"``)."""
    unit = getattr(detector, "unit", None)
    return unit if isinstance(unit, str) and unit else "counts"


def phase_tolerance_deg(detector: Detector) -> float | None:
    """How far (°) a lock-in's phase may drift from the reference reading's before it
    is worth an event (its optional ``phase_tolerance_deg``; None: no phase check)."""
    value = getattr(detector, "phase_tolerance_deg", None)
    return None if value is None else float(value)


def range_changes(detector: Detector) -> tuple[RangeChange, ...]:
    """The range changes ``detector`` saw so far (its optional ``range_changes``; none)."""
    return tuple(getattr(detector, "range_changes", ()))


class LightSource(Device, Protocol):
    """A switchable source."""

    @property
    def is_on(self) -> bool: ...

    def on(self) -> None: ...

    def off(self) -> None: ...


#: What is on the stage of a simulated instrument.
StageTarget = Literal["sample", "reference"]


class Simulated(Protocol):
    """What only a simulated backend offers (optional; see the module docstring)."""

    def begin_sample(self, index: int) -> None:
        """The next moves and readings belong to sample ``index`` (its random streams,
        its injected faults); measuring a sample again continues its streams."""
        ...

    def show(self, target: StageTarget) -> None:
        """Put the sample or the reference standard on the stage."""
        ...

    def true_positions(self) -> dict[str, float]:
        """Where the joints really are (rad), errors included."""
        ...

    def expect(self, goals: Any, index: Any) -> None:
        """A hint: the next samples ``index`` (N,) will be measured at joint ``goals``
        (N, A, rad), in order; a simulation may precompute them (readings unchanged)."""
        ...

    def snapshot(self) -> Any:
        """The state a resumed run restores (between targets, at rest), as JSON values
        (None when the backend cannot be restored)."""
        ...

    def restore(self, state: Any) -> None:
        """Continue from a `snapshot`."""
        ...
