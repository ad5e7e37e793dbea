"""What the engine tells whoever watches a session (`Observer`: the targets to do, each
one finished), and how a session is shown on one of `gonio.progress`'s displays
(`Shown`): a bar on a terminal, plain periodic lines elsewhere, nothing when quiet.

The time left is the planner's prediction for the targets still to measure (their
moves, settle and exposures), scaled by the pace measured so far: (wall time spent) /
(predicted time of the targets done), so a rig slower or faster than planned, or a
simulation thousands of times faster than the rig, is estimated by its own pace.
"""

from __future__ import annotations

import sys
import time
from typing import IO, Protocol

import numpy as np

from gonio import progress
from gonio.planner import Plan


class Observer(Protocol):
    def start(self, plan: Plan, todo: np.ndarray) -> None:
        """The run is about to measure the plan's targets ``todo`` (indices, in order)."""
        ...

    def advance(self, done: int) -> None:
        """``done`` of the targets to do are finished (measured or skipped)."""
        ...

    def close(self) -> None: ...


class Pace:
    """The estimate of the time left (see the module docstring)."""

    def __init__(self, plan: Plan, todo: np.ndarray) -> None:
        per_target = plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages
        self.cumulative = np.concatenate([[0.0], np.cumsum(per_target[todo])])
        self.started = time.monotonic()

    def left_s(self, done: int) -> float:
        """Wall seconds left after ``done`` targets."""
        spent = time.monotonic() - self.started
        predicted_done = self.cumulative[done]
        predicted_left = self.cumulative[-1] - predicted_done
        if predicted_done <= 0 or done == 0:
            return float(predicted_left)
        return float(predicted_left * spent / predicted_done)


class Unobserved:
    """Nobody watches."""

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        pass

    def advance(self, done: int) -> None:
        pass

    def close(self) -> None:
        pass


class Shown:
    """A session shown on ``display``, its time left by `Pace`."""

    def __init__(self, display: progress.Progress) -> None:
        self.display = display
        self._done = 0

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        pace = Pace(plan, todo)
        self._done = 0
        self.display.start(len(todo), "acquiring", unit="target", left_s=pace.left_s)

    def advance(self, done: int) -> None:
        self.display.advance(done - self._done)
        self._done = done

    def close(self) -> None:
        self.display.close()


def for_stream(quiet: bool, stream: IO[str] | None = None) -> Observer:
    """Nothing if ``quiet``, else the session shown on ``stream`` (a bar on a terminal,
    lines elsewhere)."""
    if quiet:
        return Unobserved()
    return Shown(progress.for_stream(False, stream or sys.stderr, done_word="acquired"))
