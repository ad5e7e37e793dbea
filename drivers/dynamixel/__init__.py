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
from drivers.dynamixel.control_table import (
    BAUD_RATES,
    DRIVE_MODE_REVERSE,
    EEPROM_END,
    EXTENDED_POSITION_LIMIT,
    FACTORY_BAUD,
    HARDWARE_ERROR_BITS,
    OPERATING_MODES,
    RAD_PER_TICK,
    TICKS_PER_REV,
    Area,
    Item,
)
from drivers.dynamixel.models import DEFAULT_MODEL, MODEL_NAMES, Model, model, model_number
from drivers.dynamixel.wire import (
    BITS_PER_BYTE,
    DEFAULT_RETURN_DELAY_S,
    poll_bytes,
    poll_seconds,
    setpoint_period,
    setpoint_seconds,
    step_seconds,
    sync_write_bytes,
)

__all__ = [
    "BAUD_RATES",
    "BITS_PER_BYTE",
    "DEFAULT_MODEL",
    "DEFAULT_RETURN_DELAY_S",
    "DRIVE_MODE_REVERSE",
    "EEPROM_END",
    "EXTENDED_POSITION_LIMIT",
    "FACTORY_BAUD",
    "HARDWARE_ERROR_BITS",
    "MODEL_NAMES",
    "OPERATING_MODES",
    "RAD_PER_TICK",
    "TICKS_PER_REV",
    "Area",
    "AxisConfig",
    "Item",
    "Model",
    "model",
    "model_number",
    "poll_bytes",
    "poll_seconds",
    "setpoint_period",
    "setpoint_seconds",
    "step_seconds",
    "sync_write_bytes",
]
