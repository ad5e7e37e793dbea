"""A Dynamixel bus's condition and recovery (`DynamixelBus`'s `health`, `check` and
`reboot`): the motors' temperatures, supply voltage and Hardware Error Status, and
rebooting the motors that report an error."""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

from drivers.base import CommError, DriverError, Health, MotorFault
from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import VOLT_PER_UNIT, decode_hardware_error, item
from drivers.dynamixel.link import DynamixelLink

_VOLTAGE = item("present_input_voltage")
_TEMPERATURE = item("present_temperature")


class Condition:
    """`DynamixelBus`'s health and recovery, over its link and axes."""

    _link: DynamixelLink
    _axes: dict[str, AxisConfig]
    _swept: set[int]
    poll_interval_s: float
    reboot_timeout_s: float

    if TYPE_CHECKING:

        def _check_open(self) -> None: ...

        def _axis(self, name: str) -> AxisConfig: ...

        def _write_profiles(self, motor_ids: Sequence[int]) -> None: ...

        def _hold(self, names: Sequence[str]) -> None: ...

    # -- recovery ----------------------------------------------------------------------
    def reboot(self, axes: Iterable[str] | None = None) -> tuple[str, ...]:
        """Reboot the motors reporting a hardware error (or those of ``axes``), wait for
        them to answer again, restore their RAM configuration (profile velocity and
        acceleration; EEPROM survives a reboot) and leave them holding where they are
        with torque on. Returns the axes rebooted.

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
        self._write_profiles(motor_ids)
        self._swept.difference_update(motor_ids)
        self._hold(names)
        link.sync_write("torque_enable", dict.fromkeys(motor_ids, 1))
        for motor_id in motor_ids:  # read back: the motor holds, or we say so
            if link.read(motor_id, "torque_enable") != 1:
                raise DriverError(f"{link.who(motor_id)} did not turn its torque back on")
        return tuple(names)

    # -- condition ---------------------------------------------------------------------
    def health(self) -> dict[str, Health]:
        """Temperature (°C), input voltage (V) and hardware error flags per axis."""
        self._check_open()
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
