"""What a stream check observes and judges: the requirements of a streaming detector
(``docs/reference/serial_detector.md``, "What the instrument must support"), a
stream's observation (`StreamRecord`), the limits and one requirement's verdict
(`Requirement`); the verdicts themselves are `gonio.workflows.stream_check.judge`'s.

Times are on the host's clock (s). A window's end on that clock is placed from the
start command: the first window ends one period after the command left, the others
follow by the device's clock (its timestamps, or the line count × the period without
them). The fastest line of a stream bounds its latency from above: ``min(received −
device clock)`` is the clock offset plus the shortest latency.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drivers.serial_detector import StreamTrace
from gonio.types import FloatArray

#: A figure of a verdict: a number, a flag, a word, or None (not measured).
Figure = float | int | bool | str | None

#: The requirements, by name, and what each says (the order of the verdict).
REQUIREMENTS: dict[str, str] = {
    "stop_acknowledged": "acknowledges STOP after its last data line, within timeout_s",
    "starts_on_command": "its first window begins when the start command arrives",
    "steady_rate": "one line per window at the asked rate, none lost",
    "timestamps": "its own timestamp on every line, increasing, at the asked rate",
    "latency": "each line arrives soon after its window ends",
    "line_time": "a line's time on the wire fits well within the period",
    "idle_after_stop": "answers a query after its streams (STOP when idle is harmless)",
}


@dataclass(frozen=True)
class Limits:
    """What passes. ``rate_tolerance``: the largest |achieved / asked − 1| of the rate,
    and of the device's clock against the host's. ``interval_tolerance``: the largest
    95th percentile of |interval − period| / period (at least one unit of the device's
    clock). ``start_tolerance``: how far the first window may begin from the command's
    arrival, and vary over the starts, as a share of the period (at least one unit of
    the device's clock): a fly sweep's stamps are off by as much. ``latency_median_s``
    and ``latency_p95_s``: the median and 95th percentile of arrival − window end (s).
    ``line_share``: the largest share of the period a line's bytes may take on the wire
    (10 bits a byte, 2 for the line ending)."""

    rate_tolerance: float = 0.01
    interval_tolerance: float = 0.1
    start_tolerance: float = 0.25
    latency_median_s: float = 0.02
    latency_p95_s: float = 0.05
    line_share: float = 0.9


#: The limits a check uses unless told otherwise.
DEFAULT_LIMITS = Limits()


@dataclass(frozen=True)
class StreamRecord:
    """One stream as observed: the driver's `StreamTrace`, each data line's arrival
    (``received_s``) and device timestamp (``device_t_s``, s; NaN where the line had
    none), the data lines heard after the stream was stopped (``data_after_stop``) and
    the driver's error when reading or stopping it failed."""

    trace: StreamTrace
    received_s: FloatArray
    device_t_s: FloatArray
    data_after_stop: int = 0
    read_error: str | None = None
    stop_error: str | None = None

    @property
    def period_s(self) -> float:
        return 1.0 / self.trace.rate_hz

    @property
    def timed(self) -> bool:
        """Every line carries the device's timestamp."""
        return bool(len(self.device_t_s)) and bool(np.all(np.isfinite(self.device_t_s)))

    def clock(self) -> FloatArray:
        """Each line's window end on the device's clock (s): its timestamp, or its count ×
        the period when some line has none."""
        if self.timed:
            return self.device_t_s
        return np.arange(len(self.received_s), dtype=np.float64) * self.period_s

    def lead_s(self) -> float:
        """How long after the command left, less one period, the first window ended as
        the fastest line places it (s): the first window's late start plus the stream's
        shortest latency; negative when it began before the command."""
        clock = self.clock()
        offset = float(np.min(self.received_s - clock))
        return float(clock[0]) + offset - self.period_s - self.trace.sent_s

    def latencies_s(self) -> FloatArray:
        """Each line's arrival less its window's end placed from the start command (s)."""
        clock = self.clock()
        ends = self.trace.sent_s + self.period_s + (clock - clock[0])
        return np.asarray(self.received_s - ends, dtype=np.float64)


@dataclass(frozen=True)
class Requirement:
    """One requirement's verdict: its ``name`` (a key of `REQUIREMENTS`), whether it
    ``passed``, a one-line ``summary`` with the measured numbers, and the ``figures``
    (name → number, s and Hz unless the name says otherwise)."""

    name: str
    passed: bool
    summary: str
    figures: dict[str, Figure] = field(default_factory=dict)
