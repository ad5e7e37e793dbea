"""A Dynamixel bus's condition and recovery (`DynamixelBus`'s `health`, `check`,
`reboot` and `recover`): the motors' temperatures, supply voltage, load and Hardware
Error Status, and rebooting the motors that report an error back into the
configuration the bus gave them when it opened."""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import VOLT_PER_UNIT, decode_hardware_error, item
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.models import DEFAULT_MODEL, Model
from drivers.errors import CommError, DriverError, MotorFault
from drivers.values import Health, Recovered

_CURRENT = item("present_current")  # Present Load on an XL430, at the same address
_VOLTAGE = item("present_input_voltage")
_TEMPERATURE = item("present_temperature")
_PRESENT = item("present_position")


class Condition:
    """`DynamixelBus`'s health and recovery, over its link and axes."""

    _link: DynamixelLink
    _axes: dict[str, AxisConfig]
    _goals: dict[str, int]
    _swept: set[int]
    configure: bool
    poll_interval_s: float
    reboot_timeout_s: float

    if TYPE_CHECKING:

        def _check_open(self) -> None: ...

        def _axis(self, name: str) -> AxisConfig: ...

        def _configure(self, motor_ids: Sequence[int] | None = None) -> None: ...

        def _write_profiles(self, motor_ids: Sequence[int]) -> None: ...

        def _hold(self, names: Sequence[str]) -> None: ...

    # -- recovery ----------------------------------------------------------------------
    def reboot(self, axes: Iterable[str] | None = None) -> tuple[str, ...]:
        """Reboot the motors reporting a hardware error (or those of ``axes``), wait for
        them to answer again, restore the configuration `open` gave them (operating
        mode, drive mode and position limits where they differ, the profile; with
        ``configure`` off only the profile) and leave them holding where they are with
        torque on. Returns the axes rebooted.

        A motor whose error is still there after the reboot raises `MotorFault` (remove
        the cause first: load, heat, supply). In extended position mode a reboot loses
        the multi-turn count (the motor comes back within one turn), so re-home such an
        axis before trusting its angle.
        """
        self._check_open()
        link = self._link
        if axes is None:
            ids = [a.motor_id for a in self._axes.values()]
            status = "hardware_error_status"
            errors = link.sync_read(ids, status, status, alerts=False)
            names = [n for n, a in self._axes.items() if errors[a.motor_id][0]]
        else:
            names = list(dict.fromkeys(self._axis(n).name for n in axes))
        if not names:
            return ()
        motor_ids = [self._axes[n].motor_id for n in names]
        for motor_id in motor_ids:
            link.reboot(motor_id)
        deadline = time.monotonic() + self.reboot_timeout_s
        for motor_id in motor_ids:
            while True:  # the status leaves before the motor restarts
                try:
                    link.ping(motor_id)
                    break
                except CommError:
                    if time.monotonic() >= deadline:
                        raise
                    time.sleep(self.poll_interval_s)
            if link.hardware_error(motor_id):
                raise link.fault(motor_id)
        if self.configure:  # as `open` did: the same code
            self._configure(motor_ids)
        else:
            self._write_profiles(motor_ids)
        self._swept.difference_update(motor_ids)
        self._hold(names)
        link.sync_write("torque_enable", dict.fromkeys(motor_ids, 1))
        for motor_id in motor_ids:  # read back: the motor holds, or we say so
            if link.read(motor_id, "torque_enable") != 1:
                raise DriverError(f"{link.who(motor_id)} did not turn its torque back on")
        return tuple(names)

    def recover(self, axis: str) -> Recovered:
        """Hold every axis where it is, reboot ``axis``'s motor back into its configuration
        (`reboot`) and read its position again: the position (rad) it was told to hold
        just before the reboot and the one it reads after. `MotorFault` if its error
        is still there after the reboot, `CommError` if it does not answer again."""
        self._check_open()
        config = self._axis(axis)
        self._hold(list(self._axes))  # every other axis too (the faulted one's goal: here)
        held = self._goals[config.name]
        self.reboot((config.name,))
        present = self._link.read(config.motor_id, _PRESENT.name)
        return Recovered(config.name, config.to_rad(held), config.to_rad(present))

    # -- condition ---------------------------------------------------------------------
    def health(self) -> dict[str, Health]:
        """Temperature (°C), input voltage (V), hardware error flags and load (signed %:
        Present Current over the model's largest Current Limit; an XL430's Present
        Load) per axis; a motor's alert does not raise."""
        self._check_open()
        ids = [a.motor_id for a in self._axes.values()]
        status = "hardware_error_status"
        errors = self._link.sync_read(ids, status, status, alerts=False)
        raw = self._link.sync_read(ids, _CURRENT.name, _TEMPERATURE.name, alerts=False)
        volts = _VOLTAGE.address - _CURRENT.address
        temperature = _TEMPERATURE.address - _CURRENT.address
        out = {}
        for name, axis in self._axes.items():
            data = raw[axis.motor_id]
            out[name] = Health(
                temperature_c=float(data[temperature]),
                voltage_v=_VOLTAGE.decode(data[volts : volts + _VOLTAGE.size]) * VOLT_PER_UNIT,
                error_flags=decode_hardware_error(errors[axis.motor_id][0]),
                load_pct=_load_pct(
                    self._link.tables.get(axis.motor_id, DEFAULT_MODEL), data[: _CURRENT.size]
                ),
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


def _load_pct(spec: Model, raw: bytes) -> float:
    """The load (signed %) in the two bytes at address 126 of a ``spec`` motor: Present
    Current over the model's largest Current Limit, or Present Load (0.1 %)."""
    if not spec.has("present_current"):
        return 0.1 * spec.item("present_load").decode(raw)
    return (
        100.0
        * spec.item("present_current").decode(raw)
        / float(spec.item("current_limit").high or 1)
    )
