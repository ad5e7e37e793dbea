"""Acquisition: the engine (`Engine`) that measures a plan's targets through the
`drivers.base` contract only (`measure_target`), reads the reference standard
(`read_standard`), consults its pause conditions between targets (`suspenders`),
recovers faulted motors when the plan says so (`MotorRecovery`), honours stop requests
and journals every raw reading. Backends are built and sessions run by
`gonio.workflows`; what is derived from the readings is `gonio.analysis`'s.

The names below load with their module when first used (`gonio.faces`): a reader of
runs that takes `gonio.acquire.recovery`'s summaries loads no engine.
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.acquire import control as control
    from gonio.acquire import observer as observer
    from gonio.acquire import recovery as recovery
    from gonio.acquire.ending import Outcome as Outcome
    from gonio.acquire.ending import Report as Report
    from gonio.acquire.engine import Engine as Engine
    from gonio.acquire.fly import poll_arrays as poll_arrays
    from gonio.acquire.fly import run_sweep as run_sweep
    from gonio.acquire.measure import TargetReading as TargetReading
    from gonio.acquire.measure import measure_target as measure_target
    from gonio.acquire.observer import Observer as Observer
    from gonio.acquire.observer import Unobserved as Unobserved
    from gonio.acquire.recovery import MotorRecovery as MotorRecovery
    from gonio.acquire.reference import Stage as Stage
    from gonio.acquire.reference import geometry_label as geometry_label
    from gonio.acquire.reference import read_standard as read_standard
    from gonio.acquire.reference import reference_pose as reference_pose
    from gonio.acquire.runtime import RunTime as RunTime
    from gonio.acquire.runtime import utc_now as utc_now
    from gonio.acquire.runtime import wall_offset as wall_offset
    from gonio.acquire.signals import RunInterrupted as RunInterrupted
    from gonio.acquire.signals import StopRequests as StopRequests
    from gonio.acquire.suspenders import SupplyBand as SupplyBand
    from gonio.acquire.suspenders import Suspender as Suspender
    from gonio.acquire.suspenders import TemperatureCeiling as TemperatureCeiling

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Engine": "engine",
    "MotorRecovery": "recovery",
    "Observer": "observer",
    "Outcome": "ending",
    "Report": "ending",
    "RunInterrupted": "signals",
    "RunTime": "runtime",
    "Stage": "reference",
    "StopRequests": "signals",
    "SupplyBand": "suspenders",
    "Suspender": "suspenders",
    "TargetReading": "measure",
    "TemperatureCeiling": "suspenders",
    "Unobserved": "observer",
    "control": "control",
    "geometry_label": "reference",
    "measure_target": "measure",
    "observer": "observer",
    "poll_arrays": "fly",
    "read_standard": "reference",
    "recovery": "recovery",
    "reference_pose": "reference",
    "run_sweep": "fly",
    "utc_now": "runtime",
    "wall_offset": "runtime",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
