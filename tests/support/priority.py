"""The CPU first for a test that keeps real time: its thread, the device threads it
starts and the device processes it spawns run at a higher scheduling priority (a lower
nice value) than the rest of the machine, then the thread's own priority comes back.

On Linux the nice value belongs to a thread (``setpriority(PRIO_PROCESS, 0, …)`` sets
the calling thread's), and a thread or a process inherits its creator's: the emulators a
test starts (serving threads, ``python -m sim…`` processes, ``gonio`` subprocesses) run
ahead of the busy processes around them, so a loaded host cannot hold back a reply past
the SDK's deadline. Only root (or a process whose RLIMIT_NICE allows it) may lower a
nice value; elsewhere the test runs at the priority it has (`ahead` says which).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

#: The nice value a real-time test runs at (-20 … 19; 0 is every ordinary process's). At
#: -20 a thread weighs 87 ordinary ones in Linux's fair scheduler, and a waking one
#: preempts them at once: beside 8 busy processes on 2 cores, and whatever else the host
#: runs, a device's reply is served within the SDK's deadline (at -10, 9 ordinary ones,
#: a loaded shared host still let a few of 670 tests miss one).
REAL_TIME_NICE = -20


@contextlib.contextmanager
def ahead(nice: int = REAL_TIME_NICE) -> Iterator[bool]:
    """Run the block (and what it starts) at ``nice``; True if the priority was raised,
    False where the process may not raise it. The calling thread's value is restored."""
    before = os.getpriority(os.PRIO_PROCESS, 0)
    try:
        os.setpriority(os.PRIO_PROCESS, 0, min(nice, before))
    except PermissionError:
        yield False
        return
    try:
        yield True
    finally:
        os.setpriority(os.PRIO_PROCESS, 0, before)
