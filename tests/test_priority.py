"""A real-time (``pty``) test runs ahead of the host's other work: its thread, the
threads and processes it starts at `REAL_TIME_NICE` (as root, as CI runs), and every
other test at the priority the suite started with."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

from tests.conftest import RAISE_PTY_PRIORITY
from tests.support.priority import (
    REAL_TIME_NICE,
    SESSION_NICE,
    SUITE_NICE,
    ahead,
    autogroup_nice,
)


def thread_nice() -> int:
    return os.getpriority(os.PRIO_PROCESS, 0)


def started_nice() -> tuple[int, int]:
    """The nice value of a thread and of a process started now."""
    seen: list[int] = []
    thread = threading.Thread(target=lambda: seen.append(thread_nice()))
    thread.start()
    thread.join()
    child = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpriority(os.PRIO_PROCESS, 0))"],
        capture_output=True,
        text=True,
        check=True,
    )
    return seen[0], int(child.stdout)


def test_ahead_raises_what_starts_inside_and_restores_the_thread() -> None:
    before = thread_nice()
    with ahead() as raised:
        inside = thread_nice()
        thread, process = started_nice()
    assert thread_nice() == before
    if not raised:  # only root may lower a nice value
        assert os.geteuid() != 0
        assert inside == before
        return
    assert inside == thread == process == min(REAL_TIME_NICE, before)
    assert started_nice() == (before, before)


def test_ahead_raises_the_sessions_group_and_restores_it() -> None:
    """Where the kernel groups by session, the group's weight is what another session's
    load competes with: raised in the block, back to the suite's starting value after."""
    if SESSION_NICE is None:
        pytest.skip("this kernel has no autogroups (/proc/self/autogroup)")
    with ahead() as raised:
        inside = autogroup_nice()
    assert autogroup_nice() == SESSION_NICE
    assert inside == (min(REAL_TIME_NICE, SESSION_NICE) if raised else SESSION_NICE)


@pytest.mark.pty
def test_a_pty_test_runs_in_the_pty_group_ahead_where_raised(
    request: pytest.FixtureRequest,
) -> None:
    group = request.node.get_closest_marker("xdist_group")
    assert group is not None and group.args == ("pty",)
    if not RAISE_PTY_PRIORITY:
        assert thread_nice() == SUITE_NICE  # the suite's own priority
    elif os.geteuid() == 0:
        assert thread_nice() <= REAL_TIME_NICE
        assert started_nice() == (thread_nice(), thread_nice())
        assert SESSION_NICE is None or autogroup_nice() == REAL_TIME_NICE


def test_any_other_test_runs_at_the_suites_priority() -> None:
    assert thread_nice() == SUITE_NICE
