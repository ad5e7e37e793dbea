"""The CPU first for a test that keeps real time: its thread, the device threads it
starts and the device processes it spawns run ahead of the rest of the machine, then
the priorities come back.

Two levers, both Linux's. The nice value belongs to a thread (``setpriority(PRIO_PROCESS,
0, …)`` sets the calling thread's), and a thread or a process inherits its creator's:
the emulators a test starts (serving threads, ``python -m sim…`` processes) run ahead of
the suite's other work. Where the kernel groups processes by session (autogroup, as
desktop and many server kernels do), a nice value ranks a thread only within its
session, and each session gets an equal share of the CPU: another session's busy
processes (another job on a shared CI host) would still hold a reply back. So the
session's own weight is raised too (``/proc/self/autogroup``) while the test runs. Only
root (or a process whose RLIMIT_NICE allows it) may raise either; elsewhere the test
runs at the priority it has (`ahead` says which).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

#: The nice value a real-time test runs at (-20 … 19; 0 is every ordinary process's). At
#: -20 a thread weighs 87 ordinary ones in Linux's fair scheduler, and a waking one
#: preempts them at once.
REAL_TIME_NICE = -20
#: The session's scheduling group, where the kernel has them ("/autogroup-N nice K").
AUTOGROUP = Path("/proc/self/autogroup")


def autogroup_nice() -> int | None:
    """The nice value of this process's session group, or None without autogroups."""
    try:
        return int(AUTOGROUP.read_text().split()[-1])
    except (OSError, ValueError, IndexError):
        return None


def set_autogroup_nice(nice: int) -> bool:
    """Set the session group's nice value; False where it may not be set."""
    try:
        AUTOGROUP.write_text(f"{nice}\n")
    except OSError:
        return False
    return True


#: The session group's nice value when the suite started (what `ahead` restores).
SESSION_NICE = autogroup_nice()
#: The process's nice value when the suite started: the priority its tests run at
#: unless raised (a benchmark may start the whole suite at another).
SUITE_NICE = os.getpriority(os.PRIO_PROCESS, 0)


@contextlib.contextmanager
def ahead(nice: int = REAL_TIME_NICE) -> Iterator[bool]:
    """Run the block (and what it starts) at ``nice``, its session group too; True if
    the thread's priority was raised, False where the process may not raise it. Both
    come back after the block (the group to its value at the suite's start)."""
    before = os.getpriority(os.PRIO_PROCESS, 0)
    try:
        os.setpriority(os.PRIO_PROCESS, 0, min(nice, before))
    except PermissionError:
        yield False
        return
    grouped = SESSION_NICE is not None and set_autogroup_nice(min(nice, SESSION_NICE))
    try:
        yield True
    finally:
        os.setpriority(os.PRIO_PROCESS, 0, before)
        if grouped and SESSION_NICE is not None:
            set_autogroup_nice(SESSION_NICE)
