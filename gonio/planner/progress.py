"""What planning shows while it runs: a tqdm bar per long stage (placing the targets,
the nearest-neighbour construction, improving the order, choosing the poses) on
standard error. A bar appears only on a terminal and only once its stage has lasted
`DELAY_S`, so small plans, pipes, logs and tests see nothing; `quiet()` hides them all.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import IO, Protocol

#: Seconds a stage runs before its bar appears.
DELAY_S = 2.0


class Stage(Protocol):
    def update(self, n: int = 1) -> object: ...


class Silent:
    """A stage nobody sees."""

    def update(self, n: int = 1) -> None:
        return None


@dataclass(frozen=True)
class _Display:
    shown: bool = True
    stream: IO[str] | None = None  # None: standard error
    delay_s: float = DELAY_S


_display: ContextVar[_Display | None] = ContextVar("gonio_planning_progress", default=None)


@contextmanager
def _using(display: _Display) -> Iterator[None]:
    token = _display.set(display)
    try:
        yield
    finally:
        _display.reset(token)


def quiet() -> AbstractContextManager[None]:
    """No planning progress inside the block (``gonio acquire -q``)."""
    return _using(_Display(shown=False))


def shown_on(stream: IO[str], delay_s: float = DELAY_S) -> AbstractContextManager[None]:
    """Progress on ``stream`` (still only if it is a terminal) after ``delay_s``."""
    return _using(_Display(True, stream, delay_s))


@contextmanager
def stage(description: str, total: int | None, unit: str = "target") -> Iterator[Stage]:
    """A stage of ``total`` steps (None: unknown); ``update(n)`` as steps finish."""
    display = _display.get() or _Display()
    if not display.shown:
        yield Silent()
        return
    from tqdm import tqdm

    bar = tqdm(
        total=total,
        desc=f"planning: {description}",
        unit=unit,
        unit_scale=True,
        file=display.stream or sys.stderr,
        delay=display.delay_s,
        disable=None,  # off unless the stream is a terminal
        leave=False,
        mininterval=0.5,
    )
    try:
        yield bar
    finally:
        bar.close()
