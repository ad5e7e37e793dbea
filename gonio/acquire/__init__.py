"""Acquisition: the engine (`Engine`) that measures a plan's targets through the
`drivers.base` contract only (`measure_target`), reads the reference standard
(`read_standard`), consults its pause conditions between targets (`suspenders`),
recovers faulted motors when the plan says so (`MotorRecovery`), honours stop requests
and journals every raw reading. Backends are built and sessions run by
`gonio.workflows`; what is derived from the readings is `gonio.analysis`'s.
"""

from gonio.acquire.ending import Outcome, Report
from gonio.acquire.engine import Engine
from gonio.acquire.measure import TargetReading, measure_target
from gonio.acquire.progress import Observer, Unobserved
from gonio.acquire.recovery import MotorRecovery
from gonio.acquire.reference import Stage, geometry_label, read_standard, reference_pose
from gonio.acquire.runtime import RunTime
from gonio.acquire.signals import RunInterrupted, StopRequests
from gonio.acquire.suspenders import SupplyBand, Suspender, TemperatureCeiling

__all__ = [
    "Engine",
    "MotorRecovery",
    "Observer",
    "Outcome",
    "Report",
    "RunInterrupted",
    "RunTime",
    "Stage",
    "StopRequests",
    "SupplyBand",
    "Suspender",
    "TargetReading",
    "TemperatureCeiling",
    "Unobserved",
    "geometry_label",
    "measure_target",
    "read_standard",
    "reference_pose",
]
