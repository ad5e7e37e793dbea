"""Ways a streaming photometer can fall short of what a fly scan needs
(``docs/reference/serial_detector.md``, "What the instrument must support"), each a knob
of `StreamQuirks`: a qualification (``gonio detector check-stream``) is tested against
the simulated photometer with each one set in turn. The default is a conforming device.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass


@dataclass(frozen=True)
class StreamQuirks:
    """How the simulated photometer's stream departs from the requirements.

    ``lines_after_stop_ack``: data lines it still sends after acknowledging ``STOP``
    (one a period). ``stop_ack_delay_s``: how long after a stream's ``STOP`` its ``OK``
    comes (real s; None: never; a ``STOP`` when idle is answered at once).
    ``start_delay_s``: the first window begins this long after ``STREAM`` arrives
    (real s) instead of at once. ``tick_aligned``: windows end on
    multiples of the period of the device's clock, not one period after the command.
    ``period_jitter``: each period is drawn uniformly within ± this fraction of it.
    ``drop_every``: every n-th line is lost (0: none). ``timestamp_missing_every``:
    every n-th line has no timestamp (``DAT <counts> <status>``; 0: none).
    ``timestamp_backward_every``: every n-th line's timestamp is two periods early
    (0: none). ``link_latency_s``: every byte the device sends reaches the host this
    much later (real s; a slow adapter).
    """

    lines_after_stop_ack: int = 0
    stop_ack_delay_s: float | None = 0.0
    start_delay_s: float = 0.0
    tick_aligned: bool = False
    period_jitter: float = 0.0
    drop_every: int = 0
    timestamp_missing_every: int = 0
    timestamp_backward_every: int = 0
    link_latency_s: float = 0.0

    def __post_init__(self) -> None:
        delays = (self.start_delay_s, self.link_latency_s, self.stop_ack_delay_s or 0.0)
        if not all(math.isfinite(d) and d >= 0 for d in delays):
            raise ValueError("stop_ack_delay_s, start_delay_s and link_latency_s must be ≥ 0")
        if not 0 <= self.period_jitter < 1:
            raise ValueError(f"period_jitter must be in [0, 1), got {self.period_jitter!r}")
        counts = (
            self.lines_after_stop_ack,
            self.drop_every,
            self.timestamp_missing_every,
            self.timestamp_backward_every,
        )
        if any(n < 0 for n in counts):
            raise ValueError("line counts must be ≥ 0")

    def first_end(self, at: float, period: float, t0: float) -> float:
        """The end of the first window (monotonic s) of a stream asked at ``at`` with
        windows ``period`` s apart, the device's clock starting at ``t0``."""
        start = at + self.start_delay_s
        if self.tick_aligned:
            return t0 + math.floor((start - t0) / period + 1) * period
        return start + period

    def next_period(self, period: float, rng: random.Random) -> float:
        """The time (s) to the next window's end."""
        if not self.period_jitter:
            return period
        return period * (1 + rng.uniform(-self.period_jitter, self.period_jitter))

    def data_line(
        self, index: int, t_ms: float, period_ms: float, counts: float, status: str
    ) -> str | None:
        """The text of the ``index``-th data line (from 0) of a window ending at ``t_ms``
        on the device's clock, or None when the line is lost."""
        if _every(self.drop_every, index):
            return None
        if _every(self.timestamp_missing_every, index):
            return f"DAT {counts!r} {status}"
        if _every(self.timestamp_backward_every, index):
            t_ms -= 2 * period_ms
        return f"DAT {t_ms:.3f} {counts!r} {status}"


def _every(n: int, index: int) -> bool:
    return n > 0 and index % n == n - 1


#: A conforming device.
CONFORMING = StreamQuirks()
