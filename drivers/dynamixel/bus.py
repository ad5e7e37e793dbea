"""`DynamixelBus`: the rig's motor axes as a `drivers.base.MotorBus` on Dynamixel X-series.

Goal positions of all axes go out in one SYNC_WRITE; Moving and Present Position come
back in one SYNC_READ, whose status packets also carry each motor's alert bit. Safety:

- a target outside its axis's limits raises `LimitError` before a byte is sent, and
  goals are also clamped to the motor's own position limits (written to its EEPROM in
  position mode), so the motor refuses what the software would;
- torque is only enabled after each goal is set to the present position (no jump);
- leaving the context (normally, on an exception, or on Ctrl-C in the middle of a
  transaction) makes every axis hold where it is and releases the port;
- a settle that does not finish in time holds the axes and raises `MotionTimeout`.

EEPROM items (operating mode, drive mode, position limits) are written only when they
differ, and only with torque off.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence

from drivers.base import DriverError, Health, LimitError, MotionTimeout, MotorFault, Resource
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import (
    MODELS,
    VOLT_PER_UNIT,
    decode_hardware_error,
    item,
)
from drivers.dynamixel.link import DynamixelLink

_MOVING = item("moving")
_PRESENT = item("present_position")
_VOLTAGE = item("present_input_voltage")
_TEMPERATURE = item("present_temperature")


class DynamixelBus(Resource):
    """A `MotorBus` of ``axes`` on the Dynamixel bus at ``port``.

    ``baud`` is the motors' rate (factory default 57 600; see docs/hardware.md to move
    to 1 Mbps); ``retries`` extra attempts per transaction; ``settle_ticks`` how close
    (in motor ticks) an axis must be to its goal to count as settled; ``configure``
    writes operating mode, drive mode, position limits and profiles on open.
    """

    def __init__(
        self,
        port: str,
        axes: Sequence[AxisConfig],
        *,
        baud: int = 57_600,
        retries: int = 3,
        latency_ms: float | None = None,
        settle_ticks: int = 2,
        poll_interval_s: float = 0.002,
        configure: bool = True,
    ) -> None:
        if not axes:
            raise ValueError("a bus needs at least one axis")
        names = [a.name for a in axes]
        ids = [a.motor_id for a in axes]
        if len(set(names)) != len(names) or len(set(ids)) != len(ids):
            raise ValueError(f"axis names and motor IDs must be unique: {names}, {ids}")
        self._axes = {a.name: a for a in axes}
        self._link = DynamixelLink(
            port,
            baud,
            retries=retries,
            latency_ms=latency_ms,
            names=dict(zip(ids, names, strict=True)),
        )
        self.settle_ticks = settle_ticks
        self.poll_interval_s = poll_interval_s
        self.configure = configure
        self.models: dict[str, str] = {}
        self._goals: dict[str, int] = {}

    # -- lifecycle ---------------------------------------------------------------------
    @property
    def axes(self) -> tuple[str, ...]:
        return tuple(self._axes)

    @property
    def port(self) -> str:
        return self._link.port_name

    def open(self) -> None:
        """Open the port, check every motor answers and is healthy, configure, hold."""
        self._link.open()
        try:
            for axis in self._axes.values():
                model = self._link.ping(axis.motor_id)
                self.models[axis.name] = MODELS.get(model, f"model {model}")
                flags = self._link.hardware_error(axis.motor_id)
                if flags:
                    raise self._link.fault(axis.motor_id)
            if self.configure:
                self._configure()
            self.torque(True)
        except BaseException:
            self._link.reset()
            self._link.close()
            raise

    def close(self) -> None:
        """Hold every axis where it is (best effort) and release the port."""
        if not self._link.is_open:
            return
        self._link.reset()
        try:
            self.stop()
        except DriverError:
            pass  # the port is released below whatever the motors say
        finally:
            self._link.close()

    def _configure(self) -> None:
        link = self._link
        ids = {a.motor_id: a for a in self._axes.values()}
        link.sync_write("torque_enable", dict.fromkeys(ids, 0))
        for motor_id, axis in ids.items():
            wanted = {"operating_mode": axis.operating_mode, "drive_mode": 0}
            if axis.mode == "position":
                low, high = axis.tick_limits()
                wanted |= {"min_position_limit": low, "max_position_limit": high}
            for name, value in wanted.items():
                if link.read(motor_id, name) != value:  # EEPROM wears: write only changes
                    link.write(motor_id, name, value)
        profiles = {m: a.profile_registers() for m, a in ids.items()}
        link.sync_write("profile_acceleration", {m: p[1] for m, p in profiles.items()})
        link.sync_write("profile_velocity", {m: p[0] for m, p in profiles.items()})

    # -- motion ------------------------------------------------------------------------
    def _axis(self, name: str) -> AxisConfig:
        try:
            return self._axes[name]
        except KeyError:
            raise DriverError(
                f"unknown axis {name!r}; the axes are {', '.join(self._axes)}"
            ) from None

    def move_to(self, targets: Mapping[str, float]) -> None:
        """Command axis angles (rad) in one SYNC_WRITE; returns at once."""
        goals: dict[str, int] = {}
        for name, angle in targets.items():
            axis = self._axis(name)
            if not axis.contains(float(angle)):
                raise LimitError(
                    f"axis {name!r}: target {angle!r} rad ({math.degrees(angle):.3f}°) is "
                    f"outside its limits [{axis.min_rad:.6f}, {axis.max_rad:.6f}] rad; "
                    "nothing was sent"
                )
            ticks = axis.to_ticks(float(angle))
            if axis.mode == "position":
                low, high = axis.tick_limits()
                ticks = min(max(ticks, low), high)
            goals[name] = ticks
        self._link.sync_write(
            "goal_position", {self._axes[n].motor_id: t for n, t in goals.items()}
        )
        self._goals.update(goals)

    def _state(self) -> dict[str, tuple[bool, int]]:
        """{axis: (moving, present ticks)} from one SYNC_READ of Moving … Present Position."""
        ids = [a.motor_id for a in self._axes.values()]
        raw = self._link.sync_read(ids, _MOVING.name, _PRESENT.name)
        offset = _PRESENT.address - _MOVING.address
        out = {}
        for name, axis in self._axes.items():
            data = raw[axis.motor_id]
            out[name] = (
                bool(data[0]),
                _PRESENT.decode(data[offset : offset + _PRESENT.size]),
            )
        return out

    def positions(self) -> dict[str, float]:
        """Axis angles (rad) read back from the motors."""
        return {name: self._axes[name].to_rad(ticks) for name, (_, ticks) in self._state().items()}

    def wait_settled(self, timeout_s: float) -> None:
        """Return once no axis is moving and each is within ``settle_ticks`` of its goal.

        On timeout every axis is told to hold and `MotionTimeout` names the laggards.
        """
        deadline = time.monotonic() + timeout_s
        while True:
            state = self._state()
            pending = {
                name: (moving, ticks - self._goals.get(name, ticks))
                for name, (moving, ticks) in state.items()
                if moving or abs(ticks - self._goals.get(name, ticks)) > self.settle_ticks
            }
            if not pending:
                return
            if time.monotonic() >= deadline:
                self.stop()
                detail = ", ".join(
                    f"{n} {'moving' if m else 'stopped'} {abs(d)} ticks from its goal"
                    for n, (m, d) in pending.items()
                )
                raise MotionTimeout(
                    f"axes did not settle within {timeout_s:g} s ({detail}); holding them"
                )
            time.sleep(self.poll_interval_s)

    def stop(self) -> None:
        """Hold every axis at its present position."""
        state = self._state()
        self._link.sync_write(
            "goal_position", {self._axes[n].motor_id: t for n, (_, t) in state.items()}
        )
        self._goals = {n: t for n, (_, t) in state.items()}

    def torque(self, on: bool) -> None:
        """Enable (after setting each goal to the present position) or disable torque."""
        ids = [a.motor_id for a in self._axes.values()]
        if on:
            self.stop()
        self._link.sync_write("torque_enable", dict.fromkeys(ids, 1 if on else 0))

    # -- condition ---------------------------------------------------------------------
    def health(self) -> dict[str, Health]:
        """Temperature (°C), input voltage (V) and hardware error flags per axis."""
        ids = [a.motor_id for a in self._axes.values()]
        status = "hardware_error_status"
        errors = self._link.sync_read(ids, status, status, alerts=False)
        raw = self._link.sync_read(ids, _VOLTAGE.name, _TEMPERATURE.name, alerts=False)
        out = {}
        for name, axis in self._axes.items():
            data = raw[axis.motor_id]
            out[name] = Health(
                temperature_c=float(data[2]),
                voltage_v=_VOLTAGE.decode(data[:2]) * VOLT_PER_UNIT,
                error_flags=decode_hardware_error(errors[axis.motor_id][0]),
            )
        return out

    def check(self) -> None:
        """Raise `MotorFault` for the first axis reporting a hardware error."""
        for name, h in self.health().items():
            if h.error_flags:
                axis = self._axes[name]
                raise MotorFault(
                    f"motor {axis.motor_id} (axis {name!r}) reports a hardware error: "
                    f"{', '.join(h.error_flags)}",
                    motor_id=axis.motor_id,
                    axis=name,
                    flags=h.error_flags,
                )
