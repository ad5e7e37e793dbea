"""A Dynamixel bus's condition and recovery (`DynamixelBus`'s `health`, `check`,
`reboot` and `recover`): the motors' temperatures, supply voltage, load and Hardware
Error Status, and rebooting the motors that report an error back into the
configuration the bus gave them when it opened.

`Condition`, held by `drivers.dynamixel.bus.DynamixelBus`, which calls it once it has
checked it is open; it sees the bus through a `ConditionContext`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.control_table import VOLT_PER_UNIT, decode_hardware_error, item
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.models import DEFAULT_MODEL, Model
from drivers.dynamixel.setup import axis_named
from drivers.errors import CommError, DriverError, MotorFault
from drivers.values import Health, Recovered

_CURRENT = item("present_current")  # Present Load on an XL430, at the same address
_VOLTAGE = item("present_input_voltage")
_TEMPERATURE = item("present_temperature")
_PRESENT = item("present_position")


@dataclass(frozen=True)
class ConditionContext:
    """What the condition uses of the bus that holds it: its link and axes (by name),
    and the bus's machinery as callables."""

    link: DynamixelLink
    axes: Mapping[str, AxisConfig]
    #: Hold the named axes where they are (within limits): their goals (ticks).
    hold: Callable[[Sequence[str]], Mapping[str, int]]
    #: Write the configuration `open` gave these motors again (after a reboot).
    restore: Callable[[Sequence[int]], None]


@dataclass(frozen=True)
class Condition:
    """The health and recovery of the motors of ``context`` (see the module docstring).
    ``timeout_s`` is how long a reboot waits for a motor to answer again, polled every
    ``poll_s`` (s)."""

    context: ConditionContext

    def reboot(
        self, axes: Iterable[str] | None, *, timeout_s: float, poll_s: float
    ) -> tuple[str, ...]:
        """Reboot the motors reporting a hardware error (or those of ``axes``), wait for
        them to answer again, restore their configuration and leave them holding with
        torque on (`DynamixelBus.reboot`). The axes rebooted."""
        c = self.context
        link = c.link
        if axes is None:
            ids = [a.motor_id for a in c.axes.values()]
            status = "hardware_error_status"
            errors = link.sync_read(ids, status, status, alerts=False)
            names = [n for n, a in c.axes.items() if errors[a.motor_id][0]]
        else:
            names = list(dict.fromkeys(axis_named(c.axes, n).name for n in axes))
        if not names:
            return ()
        motor_ids = [c.axes[n].motor_id for n in names]
        for motor_id in motor_ids:
            link.reboot(motor_id)
        deadline = time.monotonic() + timeout_s
        for motor_id in motor_ids:
            while True:  # the status leaves before the motor restarts
                try:
                    link.ping(motor_id)
                    break
                except CommError:
                    if time.monotonic() >= deadline:
                        raise
                    time.sleep(poll_s)
            if link.hardware_error(motor_id):
                raise link.fault(motor_id)
        c.restore(motor_ids)  # as `open` did: the same code
        c.hold(names)
        link.sync_write("torque_enable", dict.fromkeys(motor_ids, 1))
        for motor_id in motor_ids:  # read back: the motor holds, or we say so
            if link.read(motor_id, "torque_enable") != 1:
                raise DriverError(f"{link.who(motor_id)} did not turn its torque back on")
        return tuple(names)

    def recover(self, axis: str, *, timeout_s: float, poll_s: float) -> Recovered:
        """Hold every axis, reboot ``axis``'s motor (`reboot`) and read it again: where it
        was told to hold before and where it reads after (`DynamixelBus.recover`)."""
        c = self.context
        config = axis_named(c.axes, axis)
        goals = c.hold(list(c.axes))  # every other axis too (the faulted one's goal: here)
        held = goals[config.name]
        self.reboot((config.name,), timeout_s=timeout_s, poll_s=poll_s)
        present = c.link.read(config.motor_id, _PRESENT.name)
        return Recovered(config.name, config.to_rad(held), config.to_rad(present))

    def health(self) -> dict[str, Health]:
        """Temperature (°C), input voltage (V), hardware error flags and load (signed %)
        per axis (`DynamixelBus.health`); a motor's alert does not raise."""
        link, axes = self.context.link, self.context.axes
        ids = [a.motor_id for a in axes.values()]
        status = "hardware_error_status"
        errors = link.sync_read(ids, status, status, alerts=False)
        raw = link.sync_read(ids, _CURRENT.name, _TEMPERATURE.name, alerts=False)
        volts = _VOLTAGE.address - _CURRENT.address
        temperature = _TEMPERATURE.address - _CURRENT.address
        out = {}
        for name, axis in axes.items():
            data = raw[axis.motor_id]
            out[name] = Health(
                temperature_c=float(data[temperature]),
                voltage_v=_VOLTAGE.decode(data[volts : volts + _VOLTAGE.size]) * VOLT_PER_UNIT,
                error_flags=decode_hardware_error(errors[axis.motor_id][0]),
                load_pct=_load_pct(
                    link.tables.get(axis.motor_id, DEFAULT_MODEL), data[: _CURRENT.size]
                ),
            )
        return out

    def check(self) -> None:
        """Raise `MotorFault` for the first axis reporting a hardware error."""
        for name, h in self.health().items():
            if h.error_flags:
                axis = self.context.axes[name]
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
