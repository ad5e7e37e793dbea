"""The checks of a sweep's velocity profile (the ``sweep`` rules of `drivers.base.MotorBus`),
shared by every motor backend."""

from __future__ import annotations

import math
from collections.abc import Mapping

from drivers.errors import DriverError, LimitError


def sweep_profile(
    targets: Mapping[str, float],
    velocities: Mapping[str, float],
    accelerations: Mapping[str, float] | None,
    top_velocity: Mapping[str, float],
    top_acceleration: Mapping[str, float],
) -> dict[str, tuple[float, float]]:
    """A sweep's (velocity rad/s, acceleration rad/s²) per target axis, checked against
    the configured ``top_velocity`` / ``top_acceleration`` (the rules of ``sweep``):
    `DriverError` for an axis without a target or unknown, `LimitError` for a rate that
    is missing, not finite, not positive or above the configured one. Sends nothing."""
    accelerations = accelerations or {}
    for name in (*velocities, *accelerations):
        if name not in targets:
            raise DriverError(f"sweep: axis {name!r} has a velocity but no target")
    out = {}
    for name in targets:
        if name not in top_velocity:
            raise DriverError(f"unknown axis {name!r}; the axes are {', '.join(top_velocity)}")
        if name not in velocities:
            raise LimitError(f"sweep: axis {name!r} has no velocity; nothing was sent")
        rates = (float(velocities[name]), float(accelerations.get(name, top_acceleration[name])))
        tops = (top_velocity[name], top_acceleration[name])
        for what, rate, top, unit in zip(
            ("velocity", "acceleration"), rates, tops, ("rad/s", "rad/s²"), strict=True
        ):
            if not (math.isfinite(rate) and 0 < rate <= top * (1 + 1e-9)):
                raise LimitError(
                    f"axis {name!r}: sweep {what} {rate!r} {unit} is not in (0, {top:.6g}] "
                    f"{unit} (its configured {what}); nothing was sent"
                )
        out[name] = rates
    return out
