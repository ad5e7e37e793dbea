"""Switchable light sources: `SerialLightSwitch`, a lamp, shutter or relay switched by
line commands on a serial port (`drivers.base.LightSource`)."""

from drivers.light.serial_switch import SerialLightConfig, SerialLightSwitch

__all__ = ["SerialLightConfig", "SerialLightSwitch"]
