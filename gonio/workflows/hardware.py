"""The hardware backend of a rig file: its Dynamixel bus, its serial detector and its
light switch (if it has one), built from the rig's sections as `Devices` on the real
clock. Nothing here talks to a device until the `Devices` are opened.

A rig whose detector is ``simulated`` has no hardware detector: `ConfigError` names the
field (the simulated and rehearsal backends are built by `sim.devices`). Each builder
takes a ``port`` that replaces the rig's (a rehearsal wires the same drivers to
pseudo-terminals: `sim.rehearsal`).
"""

from __future__ import annotations

import dataclasses

from drivers.base import Clock, Devices, SystemClock
from drivers.dynamixel.bus import DynamixelBus
from drivers.light.serial_switch import SerialLightSwitch
from drivers.serial_detector.detector import SerialDetector
from gonio.rig.instrument import SerialSwitchSpec
from gonio.rig.model import Rig


def dynamixel_bus(rig: Rig, *, port: str | None = None) -> DynamixelBus:
    """The rig's motors (``bus`` and ``axes``), on ``port`` if given."""
    bus = rig.spec.bus
    return DynamixelBus(port or bus.port, rig.bus_axes(), baud=bus.baud)


def serial_detector(rig: Rig, clock: Clock, *, port: str | None = None) -> SerialDetector:
    """The rig's ``detector.interface`` (``kind: serial``; else `ConfigError`), its
    readings stamped by ``clock``, on ``port`` if given."""
    config = rig.serial_detector_config()
    if port is not None:
        config = dataclasses.replace(config, port=port)
    return SerialDetector(config, clock=clock, exposure_range_s=rig.spec.detector.exposure_range_s)


def light_switch(rig: Rig, clock: Clock, *, port: str | None = None) -> SerialLightSwitch | None:
    """The rig's ``light.switch`` (``kind: serial``), on ``port`` if given; None when the
    light cannot be switched."""
    switch = rig.spec.light.switch
    if not isinstance(switch, SerialSwitchSpec):
        return None
    config = switch.config()
    if port is not None:
        config = dataclasses.replace(config, port=port)
    return SerialLightSwitch(config, clock=clock)


def hardware_devices(rig: Rig, *, clock: Clock | None = None) -> Devices:
    """The rig's motors, detector and light as `Devices` (unopened)."""
    clock = clock or SystemClock()
    detector = serial_detector(rig, clock)  # ConfigError unless the interface is serial
    return Devices(dynamixel_bus(rig), detector, clock, light_switch(rig, clock))
