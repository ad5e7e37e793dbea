"""The real-time tests on a loaded machine: every test that talks to a device on a
pseudo-terminal (marker ``pty``: the emulated Dynamixel bus, the serial photometer and
lamp, the emulated VISA instruments, the rehearsals) and every test that bounds a wall
time (marker ``timing``), run ``--rounds`` times in a row, each round one pytest process,
beside ``--busy`` processes that spin on the CPU (8 on the 2-core machine: a load
average near 9). Prints each round's passes, failures (by name) and wall time; all
green is the requirement.

Each spinning process runs in a session of its own, at the priority this script has (as
other jobs on a shared host would). Each round's pytest runs in a session of its own
too, ahead of them where this user may say so (as root, as CI runs): at nice -20, and
where the kernel groups processes by session (autogroup, which gives every session an
equal share of the CPU whatever its processes' nice values) its session's group at
nice -20 as well (`tests.support.priority`). The emulators it starts, in its threads or
as processes, inherit both; so do its collection and imports, so that a round's wall
time is its tests' rather than the import of 50 test modules beside the spinning
processes. A failed test is listed with the first line of its error.

Run: .venv/bin/python benchmarks/load_suite.py [--rounds 10] [--busy 8]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import FrameType

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.support
import _report
from _busy import spinning
from _machine import describe

from tests.support.priority import REAL_TIME_NICE, set_autogroup_nice

ROOT = Path(__file__).resolve().parents[1]
#: The tests a round runs.
MARKERS = "pty or timing"


def files() -> list[str]:
    """The test files holding a ``pty`` or ``timing`` test (so a round collects only
    those)."""
    listed = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "--collect-only", "-p", "no:cacheprovider",
         "-m", MARKERS],
        cwd=ROOT, capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    return sorted({line.split("::")[0] for line in listed.splitlines() if "::" in line})


def ahead() -> None:
    """In the round's process, in its new session, before it runs pytest: the real-time
    tests' nice value, for the process and its session's group, where this user may set
    them."""
    with contextlib.suppress(PermissionError):
        os.setpriority(os.PRIO_PROCESS, 0, REAL_TIME_NICE)
        set_autogroup_nice(REAL_TIME_NICE)


def stop(signum: int, frame: FrameType | None) -> None:
    raise SystemExit(128 + signum)  # the spinning processes are ended on the way out


def one_round(paths: list[str]) -> tuple[int, int, list[str], float]:
    """Passed, failed, the failed tests' names and the round's wall time (s)."""
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", MARKERS,
         "-rf", *paths],
        cwd=ROOT, capture_output=True, text=True, stdin=subprocess.DEVNULL,
        preexec_fn=ahead, start_new_session=True, env={**os.environ, "COLUMNS": "400"},
    )  # fmt: skip
    wall = time.perf_counter() - started
    summary = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
    passed = int(m.group(1)) if (m := re.search(r"(\d+) passed", summary)) else 0
    failed = sum(int(n) for n in re.findall(r"(\d+) (?:failed|errors?)\b", summary))
    names = re.findall(r"^(?:FAILED|ERROR) (.+)$", done.stdout, flags=re.MULTILINE)
    if done.returncode not in (0, 1) or not summary:
        failed = max(failed, 1)
        names.append(f"pytest exit {done.returncode}: {summary or done.stderr[-300:]}")
    return passed, failed, names, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--rounds", type=int, default=10, help="pytest runs in a row (10)")
    parser.add_argument("--busy", type=int, default=8, help="spinning processes beside (8)")
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, stop)
    print(describe())
    paths = files()
    root = f"as root (at nice {REAL_TIME_NICE})" if os.geteuid() == 0 else "not as root"
    print(
        f"\nThe `{MARKERS}` tests of {len(paths)} files, {args.rounds} rounds beside "
        f"{args.busy} spinning processes on {os.cpu_count()} cores, {root}.\n"
    )
    print("| round | passed | failed | wall s | load (1 min) | failed tests |")
    print("|---:|---:|---:|---:|---:|---|")
    rounds = []
    with spinning(args.busy):  # each in a session of its own, as other jobs would be
        for n in range(1, args.rounds + 1):
            passed, failed, names, wall = one_round(paths)
            rounds.append((passed, failed, wall))
            load = os.getloadavg()[0]
            print(
                f"| {n} | {passed} | {failed} | {wall:.0f} | {load:.1f} | "
                f"{'; '.join(name.replace('|', '/') for name in names) or '-'} |",
                flush=True,
            )
    green = sum(1 for _, failed, _ in rounds if failed == 0)
    walls = sorted(wall for _, _, wall in rounds)
    print(
        f"\n{green} of {len(rounds)} rounds green; {sum(p for p, _, _ in rounds)} tests "
        f"passed, {sum(f for _, f, _ in rounds)} failed; a round took "
        f"{walls[len(walls) // 2]:.0f} s (median), {walls[-1]:.0f} s at most."
    )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The real-time tests beside busy processes")
