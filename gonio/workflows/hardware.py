"""The hardware backend of a rig file: its Dynamixel bus, its detector (a serial one, or
an instrument driven by its PyMeasure class) and its light switch (if it has one),
built from the rig's sections as `Devices` on the real
clock. Nothing here talks to a device until the `Devices` are opened.

A rig whose detector is ``simulated`` has no hardware detector: `ConfigError` names the
field (the simulated and rehearsal backends are built by `sim.virtual.devices`). Each builder
takes a ``port`` that replaces the rig's (a rehearsal wires the same drivers to
pseudo-terminals: `sim.rehearsal`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from drivers.base import Clock, Detector, SystemClock
from drivers.devices import Devices
from drivers.dynamixel.bus import DynamixelBus
from drivers.light.serial_switch import SerialLightSwitch
from drivers.serial_detector.detector import SerialDetector
from gonio.config import ConfigError
from gonio.rig import PyMeasureInterfaceSpec, Rig, SerialSwitchSpec

if TYPE_CHECKING:
    from drivers.pymeasure.detector import PyMeasureDetector


def dynamixel_bus(rig: Rig, *, port: str | None = None, clock: Clock | None = None) -> DynamixelBus:
    """The rig's motors (``bus`` and ``axes``), on ``port`` if given, their polls stamped
    by ``clock`` (default the host's monotonic clock)."""
    bus = rig.spec.bus
    return DynamixelBus(
        port or bus.port, rig.bus_axes(), baud=bus.baud, retries=bus.retries, clock=clock
    )


def serial_detector(rig: Rig, clock: Clock, *, port: str | None = None) -> SerialDetector:
    """The rig's ``detector.interface`` (``kind: serial``; else `ConfigError`), its
    readings stamped by ``clock``, on ``port`` if given."""
    config = rig.serial_detector_config()
    if port is not None:
        config = dataclasses.replace(config, port=port)
    return SerialDetector(config, clock=clock, exposure_range_s=rig.spec.detector.exposure_range_s)


def pymeasure_detector(
    rig: Rig, clock: Clock, *, resource: str | None = None, visa_library: str | None = None
) -> PyMeasureDetector:
    """The rig's ``detector.interface`` (``kind: pymeasure``; else `ConfigError`): the
    instrument driven by its PyMeasure class, its readings stamped by ``clock``, on
    ``resource`` through ``visa_library`` if given (a rehearsal's pty and pyvisa-py).
    PyMeasure and PyVISA are imported here, only for such a rig."""
    interface = rig.spec.detector.interface
    if not isinstance(interface, PyMeasureInterfaceSpec):
        where = rig.source or "rig"
        raise ConfigError(
            f"{where}: detector.interface: is {interface.kind!r}; expected 'pymeasure'"
        )
    # The `instruments` extra (pymeasure, pyvisa): loaded only for a pymeasure detector.
    try:
        from drivers.pymeasure.detector import PyMeasureDetector
    except ImportError as exc:
        where = rig.source or "rig"
        raise ConfigError(
            f"{where}: detector.interface: kind pymeasure needs PyMeasure and PyVISA "
            f"({exc.name} is missing): pip install 'gonio[instruments]'"
        ) from None
    config = interface.config()
    if resource is not None:
        config = dataclasses.replace(config, resource=resource)
    if visa_library is not None:
        config = dataclasses.replace(config, visa_library=visa_library)
    return PyMeasureDetector(
        config, clock=clock, exposure_range_s=rig.spec.detector.exposure_range_s
    )


def detector(rig: Rig, clock: Clock) -> Detector:
    """The rig's hardware detector (``serial`` or ``pymeasure``; else `ConfigError`)."""
    if isinstance(rig.spec.detector.interface, PyMeasureInterfaceSpec):
        return pymeasure_detector(rig, clock)
    return serial_detector(rig, clock)


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
    # ConfigError unless the interface is serial or pymeasure
    bus = dynamixel_bus(rig, clock=clock)
    return Devices(bus, detector(rig, clock), clock, light_switch(rig, clock))
