"""The soak's sessions: start the run, then kill, fill the disk and resume until it
completes, checking the run file after every session."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tests.soak.children import Launcher, PopenChild, spawn
from tests.soak.disk import DiskMode, fill, fsize_limit
from tests.soak.journal import finished, integrity
from tests.soak.scenario import plan_yaml, scene_yaml
from tests.soak.schedule import Kill, KillSchedule


@dataclass
class Session:
    """One spawned ``gonio acquire``: what it was asked, how it ended."""

    number: int
    argv: list[str]
    kill: Kill | None
    disk_full: bool
    pid: int = 0
    returncode: int | None = None
    killed: bool = False
    wall_s: float = 0.0
    stderr: str = ""
    finished_before: int = 0
    finished_after: int = 0
    integrity: str = ""


@dataclass
class Soak:
    """A soak's files and sessions (`run_soak` fills it)."""

    folder: Path  # the plan and scene files
    run: Path  # the run file
    targets: int
    seed: int
    faults: list[dict[str, Any]]
    sessions: list[Session] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)  # what a check found wrong
    wall_s: float = 0.0

    @property
    def plan(self) -> Path:
        return self.folder / "plan.yaml"

    @property
    def scene(self) -> Path:
        return self.folder / "scene.yaml"

    @property
    def kills(self) -> int:
        return sum(s.killed for s in self.sessions)

    def complete(self) -> bool:
        return bool(self.sessions) and self.sessions[-1].returncode == 0


def write_files(
    folder: Path, run: Path, targets: int, seed: int, faults: list[dict[str, Any]],
    acquisition: dict[str, Any] | None = None,
) -> Soak:  # fmt: skip
    """The plan and scene files of a soak in ``folder``, its run file to be ``run``."""
    folder.mkdir(parents=True, exist_ok=True)
    soak = Soak(folder, run, targets, seed, faults)
    soak.plan.write_text(plan_yaml(targets, acquisition))
    soak.scene.write_text(scene_yaml(faults, seed))
    return soak


def run_soak(
    soak: Soak,
    schedule: KillSchedule | None,
    *,
    disk: DiskMode = "rlimit",
    launch: Launcher = PopenChild,
    max_sessions: int = 1000,
    say: Callable[[str], None] = lambda line: None,
) -> Soak:
    """Start the run, then resume it until it completes, killing and filling the disk
    as ``schedule`` says (None: never: the uninterrupted run, resumed only after what
    ends it resumable by itself). Checks the run file after every session."""
    started = time.monotonic()
    before = np.zeros(0, dtype=np.int64)
    kills_left = 0 if schedule is None else schedule.kills
    for number in range(max_sessions):
        if soak.run.exists():
            argv = ["acquire", "--resume", str(soak.run), "-q"]
        else:
            argv = ["acquire", str(soak.plan), "--scene", str(soak.scene), "-o", str(soak.run),
                    "-q"]  # fmt: skip
        planning = not soak.run.exists()
        kill = None
        if schedule is not None and kills_left > 0:
            kill = schedule.next_kill(planning=planning)
        full = schedule is not None and schedule.disk_full_at(number) and soak.run.exists()
        session = Session(number, argv, kill, full, finished_before=len(before))
        filler = None
        preexec = None
        if full and schedule is not None:
            kill = session.kill = None  # let the disk fill
            if disk == "tmpfs":
                filler = fill(soak.run.parent, schedule.disk_room)
            else:
                preexec = fsize_limit(soak.run, schedule.disk_room)
        try:
            pid, rc, killed, err, wall = spawn(launch, argv, soak.run, kill, preexec=preexec)
        finally:
            if filler is not None:
                filler.unlink()
        session.pid, session.returncode, session.killed = pid, rc, killed
        session.stderr, session.wall_s = err, wall
        kills_left -= killed
        soak.sessions.append(session)
        if rc not in (0, 3) and not killed:
            soak.problems.append(f"session {number}: exit {rc}: {err.strip()[-400:]}")
            break
        if not soak.run.exists():
            continue  # killed before the run file appeared: start again
        session.integrity = integrity(soak.run)
        if session.integrity != "ok":
            soak.problems.append(f"session {number}: integrity_check: {session.integrity}")
        measured, skipped = finished(soak.run)
        now = np.union1d(measured, skipped)
        lost = np.setdiff1d(before, now)
        if lost.size:
            soak.problems.append(f"session {number}: targets lost after it: {lost[:10].tolist()}")
        session.finished_after = len(now)
        before = now
        what = "killed" if killed else f"exit {rc}"
        say(
            f"session {number:3d}: {what:7s} {'(disk full) ' if full else ''}"
            f"{session.finished_after:7d} finished, {wall:6.1f} s"
        )
        if rc == 0:
            break
    soak.wall_s = time.monotonic() - started
    if not soak.complete():
        soak.problems.append(f"the run did not complete in {len(soak.sessions)} sessions")
    return soak
