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
    from gonio.acquire.ending import Outcome as Outcome
    from gonio.acquire.ending import Report as Report
    from gonio.acquire.engine import Engine as Engine
    from gonio.acquire.measure import (
        TargetReading as TargetReading,
    )
    from gonio.acquire.measure import (
        measure_target as measure_target,
    )
    from gonio.acquire.observer import Observer as Observer
    from gonio.acquire.observer import Unobserved as Unobserved
    from gonio.acquire.recovery import MotorRecovery as MotorRecovery
    from gonio.acquire.reference import (
        Stage as Stage,
    )
    from gonio.acquire.reference import (
        geometry_label as geometry_label,
    )
    from gonio.acquire.reference import (
        read_standard as read_standard,
    )
    from gonio.acquire.reference import (
        reference_pose as reference_pose,
    )
    from gonio.acquire.runtime import RunTime as RunTime
    from gonio.acquire.signals import RunInterrupted as RunInterrupted
    from gonio.acquire.signals import StopRequests as StopRequests
    from gonio.acquire.suspenders import (
        SupplyBand as SupplyBand,
    )
    from gonio.acquire.suspenders import (
        Suspender as Suspender,
    )
    from gonio.acquire.suspenders import (
        TemperatureCeiling as TemperatureCeiling,
    )

#: Each name of the face, by the module that defines it.
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
    "geometry_label": "reference",
    "measure_target": "measure",
    "read_standard": "reference",
    "reference_pose": "reference",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
