"""``python -m tests.gonio.live.paced SECONDS ARGS…``: ``gonio ARGS…`` (an acquire) whose
progress observer sleeps SECONDS of wall time after each target, so a simulated run
(its clock virtual, thousands of times faster than the rig) lasts long enough to be
watched and controlled."""

from __future__ import annotations

import sys
import time
from typing import IO

import numpy as np

from gonio.acquire import observer
from gonio.cli import main
from gonio.planner.model import Plan


class Paced:
    def __init__(self, seconds: float) -> None:
        self.seconds = seconds

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        pass

    def advance(self, done: int) -> None:
        time.sleep(self.seconds)

    def close(self) -> None:
        pass


if __name__ == "__main__":
    seconds = float(sys.argv[1])

    def for_stream(quiet: bool, stream: IO[str] | None = None) -> Paced:
        return Paced(seconds)

    observer.for_stream = for_stream  # type: ignore[assignment]
    sys.exit(main(sys.argv[2:]))
