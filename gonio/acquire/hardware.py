"""The hardware backend of a rig file: its Dynamixel bus, its serial detector and its
light switch (if it has one), built from the rig's sections as `Devices` on the real
clock. Nothing here talks to a device until the `Devices` are opened.

A rig whose detector is ``simulated`` has no hardware detector: `ConfigError` names the
field (the simulated and rehearsal backends are built by `sim.devices`).
"""

from __future__ import annotations

from drivers.base import Clock, SystemClock
from drivers.dynamixel.bus import DynamixelBus
from drivers.light import SerialLightSwitch
from drivers.serial_detector import SerialDetector
from gonio.acquire.devices import Devices
from gonio.rig.instrument import SerialSwitchSpec
from gonio.rig.model import Rig


def hardware_devices(rig: Rig, *, clock: Clock | None = None) -> Devices:
    """The rig's motors, detector and light as `Devices` (unopened)."""
    clock = clock or SystemClock()
    spec = rig.spec
    detector = SerialDetector(
        rig.serial_detector_config(),  # ConfigError unless the interface is serial
        clock=clock,
        exposure_range_s=spec.detector.exposure_range_s,
    )
    bus = DynamixelBus(spec.bus.port, rig.bus_axes(), baud=spec.bus.baud)
    switch = spec.light.switch
    light = (
        SerialLightSwitch(switch.config(), clock=clock)
        if isinstance(switch, SerialSwitchSpec)
        else None
    )
    return Devices(bus, detector, clock, light)
