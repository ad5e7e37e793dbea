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


@dataclass
class Calibrations:
    """When the reference standard is read in a run, and what the last reading left.

    ``every``: the plan's schedule between targets; ``k``: calibrations journaled so far
    (all sessions); ``at_count``: targets measured at the last one (None: none yet);
    ``exposure_s``: the exposure (s) the last one settled on, where the next one starts
    (None: none yet). A run is calibrated before its first target and after its last.
    """

    every: Every
    k: int = 0
    at_count: int | None = None
    exposure_s: float | None = None

    def opening(self, *, resuming: bool, on_resume: bool) -> str | None:
        """Why a session reads the standard before its first target: ``start`` (the run
        has no calibration yet), ``resume`` (a resumed session, when ``on_resume``), or
        None (it does not)."""
        if self.k == 0:
            return "start"
        return "resume" if resuming and on_resume else None

    def due(self, count: int, t_s: float) -> bool:
        """Whether a scheduled one is due at ``count`` targets and run time ``t_s`` (s)."""
        return self.every.due(count, t_s)

    def closing(self, count: int, *, measuring: bool) -> bool:
        """Whether a session ends with one: when it had targets to measure
        (``measuring``), or none was read since the ``count``-th target (not again when
        a run that ended is resumed)."""
        return measuring or self.at_count != count

    def done(self, count: int, t_s: float, exposure_s: float) -> None:
        """One was journaled at ``count`` targets and run time ``t_s``, read at
        ``exposure_s`` (s)."""
        self.k += 1
        self.at_count = count
        self.exposure_s = exposure_s
        self.every.done(count, t_s)
