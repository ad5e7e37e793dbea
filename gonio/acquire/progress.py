"""How a run shows its progress: a bar on a terminal (tqdm), plain periodic lines when
the output is not a terminal, nothing when quiet.

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

from gonio.planner.model import Plan
from gonio.progress import hms


class Progress(Protocol):
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

    @property
    def total(self) -> int:
        return len(self.cumulative) - 1

    def left_s(self, done: int) -> float:
        """Wall seconds left after ``done`` targets."""
        spent = time.monotonic() - self.started
        predicted_done = self.cumulative[done]
        predicted_left = self.cumulative[-1] - predicted_done
        if predicted_done <= 0 or done == 0:
            return float(predicted_left)
        return float(predicted_left * spent / predicted_done)

    def elapsed_s(self) -> float:
        return time.monotonic() - self.started


class Quiet:
    def start(self, plan: Plan, todo: np.ndarray) -> None:
        pass

    def advance(self, done: int) -> None:
        pass

    def close(self) -> None:
        pass


class Lines:
    """A line every ``every_s`` seconds of wall time (and at the end)."""

    def __init__(self, stream: IO[str] | None = None, every_s: float = 30.0) -> None:
        self.stream = stream or sys.stderr
        self.every_s = every_s
        self.pace: Pace | None = None
        self._last = 0.0
        self._done = 0

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        self.pace = Pace(plan, todo)
        self._last = time.monotonic()

    def _line(self, done: int) -> None:
        assert self.pace is not None
        p = self.pace
        print(
            f"acquired {done}/{p.total} targets, {hms(p.elapsed_s())} elapsed, "
            f"about {hms(p.left_s(done))} left",
            file=self.stream,
            flush=True,
        )

    def advance(self, done: int) -> None:
        self._done = done
        if time.monotonic() - self._last >= self.every_s:
            self._last = time.monotonic()
            self._line(done)

    def close(self) -> None:
        if self.pace is not None and self.pace.total:
            self._line(self._done)


class Bar:
    """A tqdm bar: targets done, rate, elapsed, and the time left by `Pace`."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        self.stream = stream or sys.stderr
        self.pace: Pace | None = None
        self.bar: object | None = None

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        from tqdm import tqdm

        self.pace = Pace(plan, todo)
        self.bar = tqdm(
            total=len(todo),
            file=self.stream,
            unit="target",
            mininterval=0.2,
            bar_format="{desc} {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} "
            "[{elapsed}, {rate_fmt}, {postfix}]",
            desc="acquiring",
        )

    def advance(self, done: int) -> None:
        from tqdm import tqdm

        bar, pace = self.bar, self.pace
        assert isinstance(bar, tqdm) and pace is not None
        bar.update(done - bar.n)
        bar.set_postfix_str(f"{hms(pace.left_s(done))} left", refresh=False)

    def close(self) -> None:
        from tqdm import tqdm

        if isinstance(self.bar, tqdm):
            self.bar.close()


def for_stream(quiet: bool, stream: IO[str] | None = None) -> Progress:
    """`Quiet` if ``quiet``, a `Bar` on a terminal, else `Lines`."""
    stream = stream or sys.stderr
    if quiet:
        return Quiet()
    return Bar(stream) if stream.isatty() else Lines(stream)
