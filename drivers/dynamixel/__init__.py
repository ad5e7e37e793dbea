"""ROBOTIS Dynamixel X-series motors over Protocol 2.0.

:mod:`drivers.dynamixel.control_table` is the control table as data,
:mod:`sim.peers.dynamixel.protocol` the packet format (our own codec, used by the
emulator and to check the SDK byte for byte), :mod:`drivers.dynamixel.link` one port
through the unmodified ``dynamixel-sdk`` (with the corrections of
:mod:`drivers.dynamixel.sdk_boundary`), :mod:`drivers.dynamixel.bus` the `MotorBus`,
:mod:`drivers.dynamixel.hygiene` the checks of a bus before its first move.
The package exports the axis configuration without the serial stack (a rig file is
checked without opening a port); the bus is `drivers.dynamixel.bus.DynamixelBus`.
"""

from drivers.dynamixel.axis import AxisConfig

__all__ = ["AxisConfig"]
