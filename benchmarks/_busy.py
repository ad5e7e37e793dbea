"""Processes that spin on the CPU beside a benchmark: the load of a shared host.

`spinning(n)` starts ``n`` Python processes that loop forever, each in a session of its
own (where the kernel groups processes by session for scheduling, as many competitors
as other jobs on a shared host would be), at the priority of the caller, and kills
them on the way out.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager

SPIN = "while True: pass"


@contextmanager
def spinning(n: int) -> Iterator[list[subprocess.Popen[bytes]]]:
    """``n`` processes spinning on the CPU while the block runs (see the module
    docstring)."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    hogs = [
        subprocess.Popen(
            [sys.executable, "-c", SPIN], env=env, stdin=subprocess.DEVNULL,
            start_new_session=True,
        )
        for _ in range(n)
    ]  # fmt: skip
    try:
        yield hogs
    finally:
        for hog in hogs:
            hog.kill()
        for hog in hogs:
            hog.wait()
