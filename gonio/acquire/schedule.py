"""When something periodic is due: after a number of targets or a span of run time,
whichever comes first (calibrations, health checks)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class Every:
    """Due once ``samples`` targets were measured, or ``minutes`` of run time passed,
    since the last time (either may be None: never on that account)."""

    samples: int | None
    minutes: float | None
    last_count: int = 0
    last_t_s: float = 0.0

    def due(self, count: int, t_s: float) -> bool:
        """Whether it is due at ``count`` targets measured and run time ``t_s`` (s)."""
        if self.samples is not None and count - self.last_count >= self.samples:
            return True
        return self.minutes is not None and t_s - self.last_t_s >= 60.0 * self.minutes

    def done(self, count: int, t_s: float) -> None:
        """It happened at ``count`` targets and run time ``t_s``."""
        self.last_count, self.last_t_s = count, t_s
