"""The configuration a `DynamixelBus` gives its motors (`MotorSetup`), run when it opens
and again after a reboot (`drivers.dynamixel.condition`).

Models: `DynamixelBus.open` reads each motor's model number (PING) and from then on uses
that model's control table (:mod:`drivers.dynamixel.models`) for what it reads and
writes; a motor that is not the model its axis names (`AxisConfig.model`, the rig file's
``motor_model``), or whose model lacks the axis's operating mode, stops `open` with one
line saying so, before anything is written.

EEPROM items (operating mode, drive mode, position limits) are read first and written
only when they differ; only the motors that need such a write have their torque turned
off (and read back off) before it, so opening a configured bus never drops an arm.

Then the profiles (Profile Acceleration, Profile Velocity: RAM) of every motor.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.models import MODEL_NAMES, model
from drivers.errors import DriverError


def axis_named(axes: Mapping[str, AxisConfig], name: str) -> AxisConfig:
    """The axis called ``name`` among ``axes``; `DriverError` naming them if none is."""
    try:
        return axes[name]
    except KeyError:
        raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(axes)}") from None


@dataclass(frozen=True)
class MotorSetup:
    """Writes the configuration of ``axes`` (by name) into their motors on ``link``."""

    link: DynamixelLink
    axes: Mapping[str, AxisConfig]

    def identify(self, axis: AxisConfig) -> str:
        """PING the axis's motor and use its model's table from now on; the model's name.
        `DriverError` if it is not the model the axis names, or lacks the axis's
        operating mode."""
        link = self.link
        number = link.ping(axis.motor_id)
        spec = model(number)
        who = link.who(axis.motor_id)
        if axis.model is not None and number != axis.model:
            expected = MODEL_NAMES.get(axis.model, f"model {axis.model}")
            raise DriverError(
                f"{who} is an {spec.name} (model number {number}); the rig file expects "
                f"{expected} (axes.{axis.name}.motor_model): connect the right motor or "
                "correct the rig file; nothing was written"
            )
        if axis.operating_mode not in spec.modes:
            raise DriverError(
                f"{who} is an {spec.name}, which has no {axis.mode} mode; nothing was written"
            )
        link.tables[axis.motor_id] = spec
        return spec.name

    def configure(self, motor_ids: Sequence[int] | None = None) -> None:
        """EEPROM first (read; torque off, read back off and write only where it differs),
        then the RAM profiles, of every motor (or those of ``motor_ids``: a reboot's)."""
        link = self.link
        ids = {
            a.motor_id: a
            for a in self.axes.values()
            if motor_ids is None or a.motor_id in motor_ids
        }
        changes: dict[int, dict[str, int]] = {}
        for motor_id, axis in ids.items():
            wanted = {"operating_mode": axis.operating_mode, "drive_mode": 0}
            if axis.mode == "position":
                low, high = axis.tick_limits()
                wanted |= {"min_position_limit": low, "max_position_limit": high}
            # EEPROM wears, and writing it needs torque off: change only what differs.
            differ = {n: v for n, v in wanted.items() if link.read(motor_id, n) != v}
            if differ:
                changes[motor_id] = differ
        if changes:
            link.sync_write("torque_enable", dict.fromkeys(changes, 0))
            for motor_id in changes:
                if link.read(motor_id, "torque_enable") != 0:
                    raise DriverError(
                        f"{link.who(motor_id)} did not turn its torque off; its EEPROM "
                        f"({', '.join(changes[motor_id])}) was not written"
                    )
            for motor_id, differ in changes.items():
                for name, value in differ.items():
                    link.write(motor_id, name, value)
        self.write_profiles(list(ids))

    def write_profiles(self, motor_ids: Sequence[int]) -> None:
        """The configured Profile Acceleration and Profile Velocity of ``motor_ids``, in
        one SYNC_WRITE each."""
        by_id = {a.motor_id: a for a in self.axes.values()}
        profiles = {m: by_id[m].profile_registers() for m in motor_ids}
        self.link.sync_write("profile_acceleration", {m: p[1] for m, p in profiles.items()})
        self.link.sync_write("profile_velocity", {m: p[0] for m, p in profiles.items()})
