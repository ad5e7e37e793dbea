"""Hardware drivers: Dynamixel arm motors over serial and a serial detector.

This package imports nothing from :mod:`gonio` or :mod:`sim`; the interfaces every
backend implements live in :mod:`drivers.base`, the error hierarchy in :mod:`drivers.errors`.
"""

from drivers.base import Detector, LightSource, MotorBus
from drivers.errors import (
    CommError,
    DetectorError,
    DriverError,
    LimitError,
    MotionTimeout,
    MotorFault,
)
from drivers.values import Health, Reading

__all__ = [
    "CommError",
    "Detector",
    "DetectorError",
    "DriverError",
    "Health",
    "LightSource",
    "LimitError",
    "MotionTimeout",
    "MotorBus",
    "MotorFault",
    "Reading",
]
