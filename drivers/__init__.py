"""Hardware drivers: Dynamixel arm motors over serial and a serial detector.

This package imports nothing from :mod:`gonio` or :mod:`sim`; the interfaces every
backend implements and the error hierarchy live in :mod:`drivers.base`.
"""

from drivers.base import (
    CommError,
    Detector,
    DetectorError,
    DriverError,
    Health,
    LightSource,
    LimitError,
    MotionTimeout,
    MotorBus,
    MotorFault,
    Reading,
)

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
