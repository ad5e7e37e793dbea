"""A soak in virtual time: a simulated run of many targets with every fault class of
`sim.virtual.faults` injected, its acquiring process (``python -m gonio acquire``, a real
subprocess) SIGKILLed at random moments and resumed until the run completes, a disk
that fills up on chosen sessions; then the checks (`Soak.check`).

`run_soak` drives the sessions: a seeded schedule (`KillSchedule`) says which sessions
are killed, when (a delay after the spawn, or a few milliseconds after some number of
new samples were committed) and which meet a full disk; a session that ends with exit
3 (a motor fault, a pause that did not clear, a full disk: resumable) or is killed is
followed by ``gonio acquire --resume``. After every session the run file is checked at
once: ``PRAGMA integrity_check``, and every target finished before is still finished.

A full disk is real, not patched in: ``disk="tmpfs"`` runs the journal on a folder that
is a size-limited filesystem (the caller mounts it) and fills it with a filler file
before the session, leaving a few megabytes: SQLite meets ``ENOSPC`` and says "database
or disk is full"; the filler is removed before the next session (someone freed space).
``disk="rlimit"`` (no mount needed) limits the file size of the acquiring process
instead (RLIMIT_FSIZE): the write fails with ``EFBIG``, which SQLite reports as a disk
I/O error; gonio handles both alike (the session ends, resumable).

The journal is read with plain SQL here, not through `gonio.store`: the check does not
trust the reader it checks. What each injected fault should have caused is computed
from the scene's rules with the simulator's own `sim.virtual.faults.FaultInjector` (a pure
function of the rules, the seed, the sample and the attempt), so every handling event
is matched with its fault and every fault with its event (`Story`).

The package, one idea a module: `tests.soak.scenario` (the fault rules, plan and scene),
`tests.soak.schedule` (the kills and full disks), `tests.soak.children` (the processes and
how they are killed), `tests.soak.disk` (the full disk), `tests.soak.loop` (the sessions),
`tests.soak.journal` (the run file read back), `tests.soak.checks` (exactly once, bit for
bit) and `tests.soak.story` (faults matched with events).
"""

from tests.soak.checks import VOLATILE, exactly_once, same_samples
from tests.soak.children import Child, ForkLauncher, Launcher, PopenChild, kill_when, spawn
from tests.soak.disk import DiskMode, tmpfs
from tests.soak.journal import Event, Journal, connect, finished, integrity, progress
from tests.soak.loop import Session, Soak, run_soak, write_files
from tests.soak.scenario import (
    ACQUISITION,
    ARCH,
    ROOT,
    plan_yaml,
    realistic_faults,
    scene_yaml,
    sobol_plan,
)
from tests.soak.schedule import Kill, KillSchedule
from tests.soak.story import CALIBRATION_INDEX, Story, Struck, fault_class, story, struck

__all__ = [
    "ACQUISITION",
    "ARCH",
    "CALIBRATION_INDEX",
    "ROOT",
    "VOLATILE",
    "Child",
    "DiskMode",
    "Event",
    "ForkLauncher",
    "Journal",
    "Kill",
    "KillSchedule",
    "Launcher",
    "PopenChild",
    "Session",
    "Soak",
    "Story",
    "Struck",
    "connect",
    "exactly_once",
    "fault_class",
    "finished",
    "integrity",
    "kill_when",
    "plan_yaml",
    "progress",
    "realistic_faults",
    "run_soak",
    "same_samples",
    "scene_yaml",
    "sobol_plan",
    "spawn",
    "story",
    "struck",
    "tmpfs",
    "write_files",
]
