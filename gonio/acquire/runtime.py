"""A run's time axis: run time from the devices' clock (`RunTime`), the offset that
makes a hardware session's run time the seconds since the run's first start, and the
UTC stamps the journal writes."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime


def utc_now() -> str:
    """The wall time as ISO 8601 UTC, to the microsecond."""
    return datetime.now(UTC).isoformat(timespec="microseconds")


@dataclass(frozen=True)
class RunTime:
    """Run time (s) from the devices' clock: ``clock() + offset``."""

    clock: Callable[[], float]
    offset: float = 0.0

    def now(self) -> float:
        return self.clock() + self.offset


def wall_offset(clock_now: float, run_started_unix: float) -> float:
    """The `RunTime` offset of a hardware session: run time = seconds since the run's
    first start (wall clock), from a monotonic clock reading ``clock_now``."""
    return (time.time() - run_started_unix) - clock_now
