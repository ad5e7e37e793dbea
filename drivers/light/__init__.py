"""Switchable light sources: a lamp, shutter or relay switched by line commands on a
serial port. The package exports the configuration (`SerialLightConfig`) without the
serial stack; the driver is `drivers.light.serial_switch.SerialLightSwitch` (a
`drivers.base.LightSource`)."""

from drivers.light.config import SerialLightConfig

__all__ = ["SerialLightConfig"]
