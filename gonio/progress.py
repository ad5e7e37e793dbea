"""How long work shows its progress, one abstraction for planning stages, acquisitions
and sweeps: `Progress` (``start``, ``advance``, ``close``) with three displays, a tqdm
`Bar` on a terminal (the one terminal bar), plain periodic `Lines` when the output is
not a terminal, and `Quiet`.

A caller that can predict the time left passes ``left_s`` (the time left after ``done``
steps, in wall seconds): the acquisition passes the planner's prediction scaled by the
pace measured so far; without it the bar shows tqdm's own rate-based estimate.

Planning and exports run deep inside library code, so their stages are shown through a
context variable instead of an argument: `stage` opens a bar (on a terminal, once the
stage has lasted ``delay_s``), `step` a line naming a stage without counts (one call
into compiled code: a triangulation, a factorization), `quiet` hides them and
`shown_on` chooses the stream and the delay.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import IO, Any, Protocol

from tqdm import tqdm

#: Wall seconds left after a number of steps done.
TimeLeft = Callable[[int], float]

#: Seconds a planning stage runs before its bar appears.
DELAY_S = 2.0


def hms(seconds: float) -> str:
    """Seconds as h:mm:ss (rounded; hours unbounded)."""
    s = round(seconds)
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


class Progress(Protocol):
    def start(
        self, total: int | None, label: str, *, unit: str = "target", left_s: TimeLeft | None = None
    ) -> None:
        """``total`` steps (None: unknown) of work named ``label`` are about to run."""
        ...

    def advance(self, steps: int = 1) -> None:
        """``steps`` more steps finished."""
        ...

    def close(self) -> None: ...


class Quiet:
    """Nothing shown."""

    def start(
        self, total: int | None, label: str, *, unit: str = "target", left_s: TimeLeft | None = None
    ) -> None:
        pass

    def advance(self, steps: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


class Lines:
    """A line every ``every_s`` seconds of wall time and at the end:
    ``{done_word} {done}/{total} {unit}s, {elapsed} elapsed, about {left} left``."""

    def __init__(
        self, stream: IO[str] | None = None, every_s: float = 30.0, done_word: str = "done"
    ) -> None:
        self.stream = stream or sys.stderr
        self.every_s = every_s
        self.done_word = done_word
        self._total: int | None = None
        self._unit = "target"
        self._left: TimeLeft | None = None
        self._started = self._last = 0.0
        self._done = 0

    def start(
        self, total: int | None, label: str, *, unit: str = "target", left_s: TimeLeft | None = None
    ) -> None:
        self._total, self._unit, self._left = total, unit, left_s
        self._started = self._last = time.monotonic()
        self._done = 0

    def _line(self) -> None:
        total = "?" if self._total is None else str(self._total)
        left = "" if self._left is None else f", about {hms(self._left(self._done))} left"
        elapsed = hms(time.monotonic() - self._started)
        print(
            f"{self.done_word} {self._done}/{total} {self._unit}s, {elapsed} elapsed{left}",
            file=self.stream,
            flush=True,
        )

    def advance(self, steps: int = 1) -> None:
        self._done += steps
        if time.monotonic() - self._last >= self.every_s:
            self._last = time.monotonic()
            self._line()

    def close(self) -> None:
        if self._total:
            self._line()


class Bar:
    """A tqdm bar on ``stream`` (drawn only if it is a terminal): steps done, rate,
    elapsed and the time left (``left_s`` when given); after ``delay_s`` only, and
    removed when closed unless ``leave``."""

    def __init__(
        self,
        stream: IO[str] | None = None,
        *,
        delay_s: float = 0.0,
        leave: bool = True,
        unit_scale: bool = False,
        counted: bool = True,
    ) -> None:
        self.stream = stream or sys.stderr
        self.delay_s = delay_s
        self.leave = leave
        self.unit_scale = unit_scale  # counts shown as 1.2k, 3.4M
        self.counted = counted  # False: the label alone (a step that cannot count)
        self._bar: tqdm[Any] | None = None
        self._left: TimeLeft | None = None

    def start(
        self, total: int | None, label: str, *, unit: str = "target", left_s: TimeLeft | None = None
    ) -> None:
        self._left = left_s
        fmt = None if self.counted else "{desc} …"
        if left_s is not None:
            fmt = (
                "{desc} {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} "
                "[{elapsed}, {rate_fmt}, {postfix}]"
            )
        self._bar = tqdm(
            total=total,
            desc=label,
            unit=unit,
            unit_scale=self.unit_scale,
            file=self.stream,
            delay=self.delay_s,
            disable=None,  # off unless the stream is a terminal
            leave=self.leave,
            mininterval=0.2,
            bar_format=fmt,
        )

    def advance(self, steps: int = 1) -> None:
        bar = self._bar
        if bar is None:
            return
        bar.update(steps)
        if self._left is not None:
            bar.set_postfix_str(f"{hms(self._left(int(bar.n)))} left", refresh=False)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def for_stream(quiet: bool, stream: IO[str] | None = None, done_word: str = "done") -> Progress:
    """`Quiet` if ``quiet``, a `Bar` on a terminal, else `Lines`."""
    stream = stream or sys.stderr
    if quiet:
        return Quiet()
    return Bar(stream) if stream.isatty() else Lines(stream, done_word=done_word)


# -- planning stages -------------------------------------------------------------------
@dataclass(frozen=True)
class _Display:
    shown: bool = True
    stream: IO[str] | None = None  # None: standard error
    delay_s: float = DELAY_S


_display: ContextVar[_Display | None] = ContextVar("gonio_stage_progress", default=None)


@contextmanager
def _using(display: _Display) -> Iterator[None]:
    token = _display.set(display)
    try:
        yield
    finally:
        _display.reset(token)


def quiet() -> AbstractContextManager[None]:
    """No stage progress inside the block (``gonio acquire -q``)."""
    return _using(_Display(shown=False))


def shown_on(stream: IO[str], delay_s: float = DELAY_S) -> AbstractContextManager[None]:
    """Stage progress on ``stream`` (still only if it is a terminal) after ``delay_s``."""
    return _using(_Display(True, stream, delay_s))


def stage(
    description: str, total: int | None, unit: str = "target", *, work: str = "planning"
) -> AbstractContextManager[Progress]:
    """A stage of ``total`` steps (None: unknown) of ``work`` (planning, export), shown as
    configured by `quiet` / `shown_on` (default: standard error, after `DELAY_S`)."""
    return _stage(f"{work}: {description}", total, unit, counted=True)


def step(description: str, *, work: str) -> AbstractContextManager[Progress]:
    """A stage of ``work`` that cannot count its progress (one call into compiled code),
    shown by its description alone while it runs, as configured by `quiet` /
    `shown_on`: a bar appears when a step advances, so only a display without delay
    (``shown_on(stream, delay_s=0)``) shows it."""
    return _stage(f"{work}: {description}", None, "step", counted=False)


@contextmanager
def _stage(label: str, total: int | None, unit: str, *, counted: bool) -> Iterator[Progress]:
    display = _display.get() or _Display()
    shown: Progress = (
        Bar(display.stream, delay_s=display.delay_s, leave=False, unit_scale=True, counted=counted)
        if display.shown
        else Quiet()
    )
    shown.start(total, label, unit=unit)
    try:
        yield shown
    finally:
        shown.close()
