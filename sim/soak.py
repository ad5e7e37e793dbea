"""A soak in virtual time: a simulated run of many targets with every fault class of
`sim.faults` injected, its acquiring process (``python -m gonio acquire``, a real
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
from the scene's rules with the simulator's own `sim.faults.FaultInjector` (a pure
function of the rules, the seed, the sample and the attempt), so every handling event
is matched with its fault and every fault with its event (`Story`).
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import resource
import signal
import sqlite3
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol

import numpy as np
import yaml

from sim.devices.detector import DETECTOR_KINDS
from sim.faults import MOTOR_KINDS, FaultInjector, FaultRule
from sim.physics.streams import FAULT, Streams

ROOT = Path(__file__).resolve().parents[1]
ARCH = ROOT / "configs" / "rigs" / "arch.yaml"
#: The first calibration reading's sample index (`gonio.acquire.reference`: reading
#: ``k`` of the reference uses this + 2k, its dark + 2k + 1).
CALIBRATION_INDEX = 1 << 40
DiskMode = Literal["tmpfs", "rlimit"]


def realistic_faults(targets: int) -> list[dict[str, Any]]:
    """The soak's fault rules for a run of ``targets`` samples: rates per sample of the
    order users report (a status packet lost in a thousand, a detector timeout in two
    thousand, a motor's hardware error a few times a week), bursts longer than the
    plan's retries, two health pauses that last hours (one clears within the plan's
    pause timeout, the other outlasts it) and brief supply sags."""
    return [
        {"kind": "comm_error", "packet": "lost", "rate": 1e-3},
        {"kind": "comm_error", "packet": "corrupt", "rate": 5e-4, "burst": 2},
        {"kind": "comm_error", "packet": "lost", "rate": 3e-5, "burst": 5},
        {"kind": "detector_error", "rate": 5e-4},
        {"kind": "detector_error", "rate": 2e-5, "burst": 4},
        {"kind": "saturated", "rate": 1e-3},
        {"kind": "motor_fault", "rate": 2e-5, "axis": "detector_elevation", "flags": ["overload"]},
        {"kind": "motor_fault", "rate": 1e-5, "axis": "light_elevation", "flags": ["overheating"]},
        {"kind": "motion_timeout", "rate": 1e-5},
        {"kind": "overheat", "at": [int(0.3 * targets)], "axis": "detector_azimuth",
         "temperature_c": 74.0, "for_s": 2.5 * 3600},
        {"kind": "supply_sag", "at": [int(0.6 * targets)], "voltage_v": 9.2, "for_s": 5 * 3600},
        {"kind": "supply_sag", "rate": 2e-5, "voltage_v": 9.6, "for_s": 600.0},
    ]  # fmt: skip


#: How the plan runs: a calibration every hour, health every 100 targets or 5 min, a
#: paused run checks again every 30 s and gives up (resumable) after 4 h.
ACQUISITION: dict[str, Any] = {
    "calibration": {"every_minutes": 60, "averages": 4},
    "on_fault": {"retries": 2, "then": "skip"},
    "health": {"every_samples": 100, "every_minutes": 5, "poll_s": 30,
               "pause_timeout_minutes": 240},
}  # fmt: skip


def plan_yaml(targets: int, acquisition: dict[str, Any] | None = None) -> str:
    """A Sobol plan of ``targets`` on the arch rig (ordered without local search: the
    soak is of the acquisition, not of the planner)."""
    spec = {
        "name": "soak",
        "rig": str(ARCH),
        "parametrization": "hybrid",
        "isotropic": True,
        "sampling": {"strategy": "sobol", "target": targets, "seed": 1},
        "exposure": {"seconds": 0.5, "averages": 4},
        "max_moves": 0,
        "kicks": 0,
        "time_budget_s": 5,
        "acquisition": acquisition or ACQUISITION,
    }
    return yaml.safe_dump(spec, sort_keys=False)


def scene_yaml(faults: list[dict[str, Any]], seed: int) -> str:
    """Brushed metal with noise, drift, backlash and repeatability (every random stream
    and the motors' state matter to a resume), and ``faults``."""
    spec = {
        "name": "soak",
        "material": {"name": "ggx_anisotropic", "alpha_x": 0.05, "alpha_y": 0.25,
                     "fresnel": "conductor", "ior": 1.2, "k": 7.0},
        "source": {"irradiance_w_m2": 1.0},
        "detector": {"responsivity_a_w": 0.5, "dark_current_e_s": 2.0e5, "read_noise_e": 30,
                     "full_well_e": 1.0e10, "adc_bits": 24},
        "effects": {"shot_noise": None, "read_noise": None, "quantization": None,
                    "saturation": None,
                    "source_drift": {"rate_per_hour": 0.02, "amplitude": 0.005, "period_s": 900},
                    "position_error": {"ticks": True, "backlash_deg": 0.1,
                                       "repeatability_deg": 0.02}},
        "faults": faults,
        "seed": seed,
    }  # fmt: skip
    return yaml.safe_dump(spec, sort_keys=False)


# -- the schedule -------------------------------------------------------------------------


@dataclass(frozen=True)
class Kill:
    """When a session is killed: ``after`` new samples committed (0: from the spawn),
    then ``delay_s`` more."""

    after: int
    delay_s: float


@dataclass
class KillSchedule:
    """Seeded: ``kills`` kills spread over a run of ``targets`` (a quarter of them at
    any moment within ``startup_s`` of the spawn: opening, reading the run, restoring;
    the rest within 20 ms of a random number of new samples), and the sessions that
    meet a full disk (``disk_full`` of them, spread among the first sessions)."""

    seed: int
    kills: int
    targets: int
    disk_full: int = 0
    startup_s: float = 3.0
    disk_room: int = 4 << 20  # bytes a full disk leaves the session
    _rng: random.Random = field(init=False)
    _full: set[int] = field(init=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)
        spacing = max(2, self.kills + self.disk_full + 1)
        self._full = {2 + k * spacing // max(self.disk_full, 1) for k in range(self.disk_full)}

    def next_kill(self, *, planning: bool = False) -> Kill:
        """The next kill; ``planning``: of a session that plans first (a new run),
        killed only once it measures (a kill while it plans would only plan again)."""
        rng = self._rng
        if rng.random() < 0.25 and not planning:
            return Kill(0, rng.uniform(0.0, self.startup_s))
        mean = max(2, self.targets // max(self.kills, 1))
        return Kill(rng.randint(1, 2 * mean - 1), rng.uniform(0.0, 0.02))

    def disk_full_at(self, session: int) -> bool:
        """Whether spawn number ``session`` (0 = the first) meets a full disk."""
        return session in self._full


# -- one session ----------------------------------------------------------------------------


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


def _connect(path: Path) -> sqlite3.Connection:
    return sqlite3.connect(path, timeout=30.0, isolation_level=None)


def progress(conn: sqlite3.Connection) -> int:
    """The highest target committed (targets are measured in index order), −1 if none."""
    try:
        row = conn.execute("SELECT MAX(target) FROM samples").fetchone()
    except sqlite3.Error:
        return -1
    return -1 if row is None or row[0] is None else int(row[0])


def integrity(path: Path) -> str:
    """``PRAGMA integrity_check`` of ``path`` ('ok' when sound)."""
    conn = _connect(path)
    try:
        return "\n".join(str(r[0]) for r in conn.execute("PRAGMA integrity_check"))
    finally:
        conn.close()


def finished(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(targets measured, targets skipped) in ``path``, each sorted."""
    conn = _connect(path)
    try:
        measured = np.array([r[0] for r in conn.execute("SELECT target FROM samples")], np.int64)
        skipped = [
            r[0]
            for r in conn.execute("SELECT target FROM events WHERE kind = 'skip'")
            if r[0] is not None
        ]
    finally:
        conn.close()
    return np.sort(measured), np.sort(np.array(skipped, dtype=np.int64))


def _fill(folder: Path, leave_bytes: int) -> Path:
    """A filler file taking all the free space of ``folder``'s filesystem but
    ``leave_bytes``."""
    filler = folder / "filler.bin"
    stats = os.statvfs(folder)
    free = stats.f_bavail * stats.f_frsize
    size = max(free - leave_bytes, 0)
    with open(filler, "wb") as f:
        os.posix_fallocate(f.fileno(), 0, max(size, 1))
    return filler


def _fsize_limit(path: Path, extra: int) -> Callable[[], None]:
    """A ``preexec_fn`` that limits the child's file sizes to ``extra`` bytes beyond
    the largest of the run's files now."""
    sizes = [Path(f"{path}{s}").stat().st_size for s in ("", "-wal") if Path(f"{path}{s}").exists()]
    limit = max(sizes, default=0) + extra

    def limited() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    return limited


class Child(Protocol):
    """A started ``gonio`` process: `PopenChild` or a fork (`ForkLauncher`)."""

    pid: int

    def poll(self) -> int | None: ...
    def kill(self) -> None: ...
    def finish(self, timeout_s: float) -> tuple[int, str]:
        """Wait for the end: (return code, −9 when SIGKILLed; its stderr)."""


class PopenChild:
    """``python -m gonio ARGV`` in a new interpreter (what a user runs)."""

    def __init__(self, argv: Sequence[str], preexec: Callable[[], None] | None) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "gonio", *argv],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            cwd=ROOT,
            preexec_fn=preexec,
        )
        self.pid = self.proc.pid

    def poll(self) -> int | None:
        return self.proc.poll()

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)

    def finish(self, timeout_s: float) -> tuple[int, str]:
        try:
            _, err = self.proc.communicate(timeout=timeout_s)
        except BaseException:
            self.proc.kill()
            self.proc.wait()
            raise
        return self.proc.returncode, err.decode(errors="replace")


class ForkLauncher:
    """Children forked from this process that run ``main(ARGV)`` (the CLI's entry
    point, passed in: everything already imported, so a session starts in
    milliseconds; for tests)."""

    def __init__(self, main: Callable[[list[str]], int]) -> None:
        self.main = main

    def __call__(self, argv: Sequence[str], preexec: Callable[[], None] | None) -> Child:
        return ForkChild(self.main, list(argv), preexec)


class ForkChild:
    def __init__(
        self, main: Callable[[list[str]], int], argv: list[str], preexec: Callable[[], None] | None
    ) -> None:
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns
            code = 70
            try:
                os.close(read)
                null = os.open(os.devnull, os.O_WRONLY)
                os.dup2(null, 1)
                os.dup2(write, 2)
                sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115
                sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115
                if preexec is not None:
                    preexec()
                code = int(main(argv))
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except BaseException as exc:
                with contextlib.suppress(BaseException):
                    os.write(2, f"{type(exc).__name__}: {exc}\n".encode())
            finally:
                with contextlib.suppress(BaseException):
                    sys.stderr.flush()
                os._exit(code)
        os.close(write)
        self.pid = pid
        self._read = read
        self._status: int | None = None

    def poll(self) -> int | None:
        if self._status is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid == 0:
                return None
            self._status = os.waitstatus_to_exitcode(status)
        return self._status

    def kill(self) -> None:
        os.kill(self.pid, signal.SIGKILL)

    def finish(self, timeout_s: float) -> tuple[int, str]:
        chunks = []
        while chunk := os.read(self._read, 65536):
            chunks.append(chunk)
        os.close(self._read)
        if self._status is None:
            _, status = os.waitpid(self.pid, 0)
            self._status = os.waitstatus_to_exitcode(status)
        return self._status, b"".join(chunks).decode(errors="replace")


Launcher = Callable[[Sequence[str], Callable[[], None] | None], Child]


def spawn(
    launch: Launcher,
    argv: Sequence[str],
    run: Path,
    kill: Kill | None,
    *,
    preexec: Callable[[], None] | None = None,
    timeout_s: float = 3600.0,
) -> tuple[int, int, bool, str, float]:
    """Run ``gonio`` with ``argv``; SIGKILL it as ``kill`` says (None: never).
    (pid, return code, killed, stderr, wall seconds)."""
    started = time.monotonic()
    child = launch(argv, preexec)
    killed = False
    try:
        if kill is not None:
            killed = _kill_when(child, run, kill, started + timeout_s)
        rc, err = child.finish(max(started + timeout_s - time.monotonic(), 1.0))
    except BaseException:  # the soak itself interrupted: leave no child behind
        if child.poll() is None:
            child.kill()
        with contextlib.suppress(BaseException):
            child.finish(5.0)
        raise
    return child.pid, rc, killed and rc == -signal.SIGKILL, err, time.monotonic() - started


def _kill_when(child: Child, run: Path, kill: Kill, deadline: float) -> bool:
    """SIGKILL ``child`` when ``kill`` says; whether it was still running then."""
    if kill.after > 0:
        conn: sqlite3.Connection | None = None
        start = None
        try:
            while child.poll() is None and time.monotonic() < deadline:
                if conn is None and run.exists():
                    conn = _connect(run)
                if conn is not None:
                    now = progress(conn)
                    start = now if start is None else start
                    if now - start >= kill.after:
                        break
                time.sleep(0.002)
        finally:
            if conn is not None:
                conn.close()
    end = time.monotonic() + kill.delay_s
    while child.poll() is None and time.monotonic() < end:
        time.sleep(0.001)
    if child.poll() is not None:
        return False
    child.kill()
    return True


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
                filler = _fill(soak.run.parent, schedule.disk_room)
            else:
                preexec = _fsize_limit(soak.run, schedule.disk_room)
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


# -- reading the journal back -------------------------------------------------------------


@dataclass(frozen=True)
class Event:
    id: int
    session: int
    kind: str
    target: int | None
    t_s: float
    data: dict[str, Any]


@dataclass
class Journal:
    """What a run file says, read with plain SQL."""

    events: list[Event]
    sessions: list[tuple[int, str | None, int]]  # (id, outcome, pid)
    samples: dict[str, np.ndarray]  # column → values, ordered by target
    targets: int  # the plan's

    @classmethod
    def read(cls, path: Path) -> Journal:
        conn = _connect(path)
        try:
            events = [
                Event(
                    int(i), int(s), str(k), None if t is None else int(t), float(ts), json.loads(d)
                )
                for i, s, k, t, ts, d in conn.execute(
                    "SELECT id, session, kind, target, t_s, data FROM events ORDER BY id"
                )
            ]
            sessions = [
                (int(i), o, int(json.loads(info).get("pid", 0)))
                for i, o, info in conn.execute("SELECT id, outcome, info FROM sessions")
            ]
            cursor = conn.execute("SELECT * FROM samples ORDER BY target")
            names = [c[0] for c in cursor.description]
            rows = cursor.fetchall()
            plan = json.loads(conn.execute("SELECT value FROM meta WHERE key = 'plan_text'")
                              .fetchone()[0])  # fmt: skip
        finally:
            conn.close()
        columns = {n: np.array([r[k] for r in rows], dtype=object) for k, n in enumerate(names)}
        targets = int(yaml.safe_load(plan)["sampling"]["target"])
        return cls(events, sessions, columns, targets)

    def of_kind(self, kind: str) -> list[Event]:
        return [e for e in self.events if e.kind == kind]


#: Sample columns a resume may change: the session, the wall clock, the attempts (a
#: retried sample resumed after its failed attempt counts only its session's).
VOLATILE = frozenset({"session", "utc", "attempts"})


def same_samples(got: Journal, want: Journal) -> list[str]:
    """Where two runs' samples differ (every column but `VOLATILE`, bit for bit: floats
    compared as their IEEE bits) and their calibrations and skips; empty: identical."""
    out = []
    if set(got.samples) != set(want.samples):
        return ["the sample columns differ"]
    for name, value in want.samples.items():
        if name in VOLATILE:
            continue
        mine = got.samples[name]
        if len(mine) != len(value):
            return [f"{len(mine)} samples against {len(value)}"]
        floats = [v for v in value.tolist() if v is not None]
        if floats and all(isinstance(v, float) for v in floats):
            a = np.array([np.nan if v is None else v for v in mine.tolist()], dtype=np.float64)
            b = np.array([np.nan if v is None else v for v in value.tolist()], dtype=np.float64)
            differ = np.flatnonzero(a.view(np.int64) != b.view(np.int64))
        else:
            differ = np.flatnonzero(np.array([x != y for x, y in zip(mine, value, strict=True)]))
        if differ.size:
            out.append(f"{name}: {differ.size} samples differ (first: row {int(differ[0])})")

    def calibrations(j: Journal) -> list[Any]:
        return [(e.t_s, e.data.get("k"), e.data.get("reference"), e.data.get("dark"))
                for e in j.of_kind("calibration")]  # fmt: skip

    if calibrations(got) != calibrations(want):
        out.append("the calibrations differ")
    skips = [sorted(e.target for e in j.of_kind("skip") if e.target is not None)
             for j in (got, want)]  # fmt: skip
    if skips[0] != skips[1]:
        out.append("the skipped targets differ")
    return out


# -- what the faults should have caused -----------------------------------------------------


@dataclass(frozen=True)
class Struck:
    """An injected fault that strikes: its rule, the sample and the attempt."""

    rule: FaultRule
    index: int
    attempt: int
    device: Literal["motor", "detector"]


def struck(
    rules: Sequence[FaultRule], seed: int, indices: np.ndarray, attempts: int
) -> list[Struck]:
    """Every (sample, attempt < ``attempts``) at which a rule strikes, by device, for
    the sample ``indices`` (as `FaultInjector.fired` decides: the first rule of a
    device's kinds that fires)."""
    streams = Streams(seed)
    injector = FaultInjector(tuple(rules), streams)
    # Vectorized first pass: which samples any rule may strike at all.
    candidates = np.zeros(len(indices), dtype=np.bool_)
    for k, r in enumerate(rules):
        if r.at is not None:
            candidates |= np.isin(indices, np.array(r.at, dtype=np.int64))
        elif r.rate:
            u = streams.uniform(indices, FAULT + k, 1)[:, 0]
            candidates |= u < r.rate
    out = []
    devices: tuple[tuple[Literal["motor", "detector"], frozenset[str]], ...] = (
        ("motor", MOTOR_KINDS),
        ("detector", DETECTOR_KINDS),
    )
    for i in indices[candidates].tolist():
        for a in range(attempts):
            for device, kinds in devices:
                rule = injector.fired(i, a, kinds)
                if rule is not None:
                    out.append(Struck(rule, int(i), a, device))
    return out


def fault_class(rule: FaultRule) -> str:
    """The name a fault is reported under."""
    if rule.kind == "comm_error":
        burst = f", bursts of {rule.burst}" if rule.burst > 1 else ""
        return f"status packet {rule.packet}{burst}"
    if rule.kind == "motor_fault":
        return f"motor {', '.join(rule.flags)}"
    if rule.kind == "detector_error":
        return "detector timeout" + (f", bursts of {rule.burst}" if rule.burst > 1 else "")
    if rule.kind == "overheat":
        return f"overheat ({rule.for_s / 3600:g} h)" if rule.for_s >= 3600 else "overheat"
    if rule.kind == "supply_sag":
        return f"supply sag ({rule.for_s / 3600:g} h)" if rule.for_s >= 3600 else "supply sag"
    return rule.kind.replace("_", " ")


# -- the story the journal tells ----------------------------------------------------------


@dataclass
class Story:
    """Each injected fault matched with its handling in the journal, and each handling
    event with a fault; ``classes``: per fault class, (struck, handled, how);
    ``problems``: what does not match."""

    classes: dict[str, tuple[int, int, str]] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    counts: Counter[str] = field(default_factory=Counter)  # events by kind
    outcomes: Counter[str] = field(default_factory=Counter)  # sessions by outcome
    instrument_s: float = 0.0  # virtual time covered
    paused_s: float = 0.0  # of it, in health pauses


def _error_of(event: Event) -> str:
    if event.kind == "skip":
        return str(event.data.get("reason", "")).split(" ", 1)[0]
    return str(event.data.get("error", ""))


_HANDLING = {
    "comm_error": "CommError",
    "detector_error": "DetectorError",
    "motor_fault": "MotorFault",
    "motion_timeout": "MotionTimeout",
}


def story(soak: Soak, journal: Journal) -> Story:
    """Match the faults the scene's rules strike with the journal's events (see
    `Story`), and the sessions with the processes the soak ran."""
    out = Story()
    rules = tuple(FaultRule.model_validate(r) for r in soak.faults)
    n = journal.targets
    calibrations = len(journal.of_kind("calibration"))
    indices = np.concatenate(
        [np.arange(n, dtype=np.int64), CALIBRATION_INDEX + np.arange(2 * calibrations + 4)]
    )
    strikes = struck(rules, soak.seed, indices, 16)
    handling = [e for e in journal.events if e.kind in ("retry", "skip", "fault")]
    by_key: dict[tuple[int, str], list[Event]] = {}
    for e in handling:
        state = e.data.get("sim_state") or {}
        by_key.setdefault((int(state.get("sample", e.target or -1)), _error_of(e)), []).append(e)
    explains = {(s.index, _HANDLING[s.rule.kind]) for s in strikes if s.rule.kind in _HANDLING}
    measured = set(journal.samples["target"].tolist())
    rows = journal.samples["target"].tolist()
    remeasured = dict(zip(rows, journal.samples["remeasured"].tolist(), strict=True))
    settled = dict(zip(rows, journal.samples["settled_s"].tolist(), strict=True))
    pauses = [e for e in journal.of_kind("pause") if e.data.get("reason") == "health"]
    tally: dict[str, list[int]] = {}
    hows: dict[str, Counter[str]] = {}
    for s in strikes:
        if s.attempt > 0:
            continue  # a burst is one fault
        name = fault_class(s.rule)
        counts = tally.setdefault(name, [0, 0])
        how = hows.setdefault(name, Counter())
        calibration = s.index >= CALIBRATION_INDEX
        if s.rule.kind in _HANDLING:
            events = by_key.get((s.index, _HANDLING[s.rule.kind]), [])
            if not events:
                if calibration or s.index not in measured:
                    continue  # not reached: a calibration not taken, a sample skipped before
                out.problems.append(f"{name} at sample {s.index}: no handling event")
                counts[0] += 1
                continue
            counts[0] += 1
            counts[1] += 1
            kinds = {e.kind for e in events}
            where = " in a calibration" if calibration else ""
            if "skip" in kinds:
                how[f"skipped by policy after {len(events) - 1} retries"] += 1
            elif "fault" in kinds:
                how[f"stopped resumable{where}, resumed"] += 1
            else:
                how[f"retried ×{len(events)}{where}"] += 1
        elif s.rule.kind == "saturated":
            if calibration or s.index not in measured:
                continue
            counts[0] += 1
            if remeasured.get(s.index, 0) > 0:
                counts[1] += 1
                how["measured again at a shorter exposure"] += 1
            else:
                out.problems.append(f"{name} at sample {s.index}: not measured again")
        elif s.rule.kind in ("overheat", "supply_sag") and not calibration:
            counts[0] += 1
            t0 = settled.get(s.index)
            if t0 is None:
                out.problems.append(f"{name} at sample {s.index}: the sample is missing")
                continue
            word = "°C" if s.rule.kind == "overheat" else "supply"
            seen = [
                p for p in pauses
                if t0 - 600 <= p.t_s <= t0 + s.rule.for_s
                and any(word in q for q in p.data["problems"])
            ]  # fmt: skip
            if seen:
                counts[1] += 1
                how["paused (health), went on when it cleared"] += 1
            else:
                how["not seen by a health check"] += 1
    for name, (a, b) in tally.items():
        out.classes[name] = (a, b, "; ".join(f"{k}: {v}" for k, v in sorted(hows[name].items())))
    for e in journal.events:
        out.counts[e.kind] += 1
    for key, events in by_key.items():
        if key not in explains:
            out.problems.append(f"{len(events)} {events[0].kind} events at sample {key[0]} "
                                f"({key[1]}): no injected fault")  # fmt: skip
    # Sessions: each ends as its process did; each after the first starts with a resume.
    first_event: dict[int, Event] = {}
    for e in journal.events:
        first_event.setdefault(e.session, e)
    processes = {s.pid: s for s in soak.sessions}
    finished_before = 0
    done_by_session: Counter[int] = Counter(journal.samples["session"].tolist())
    for e in journal.of_kind("skip"):
        done_by_session[e.session] += 1
    for k, (sid, outcome, pid) in enumerate(journal.sessions):
        out.outcomes[outcome or "none (killed or disk full)"] += 1
        proc = processes.get(pid)
        head = first_event.get(sid)
        if head is not None:
            want = "start" if k == 0 else "resume"
            if head.kind != want:
                out.problems.append(f"session {sid} begins with {head.kind}, not {want}")
            elif k and head.data.get("targets_left") != n - finished_before:
                out.problems.append(
                    f"session {sid}: resume says {head.data.get('targets_left')} targets left, "
                    f"the journal {n - finished_before}"
                )
        finished_before += done_by_session[sid]
        if proc is None:
            out.problems.append(f"session {sid}: no process of the soak had pid {pid}")
            continue
        if proc.killed and outcome is not None:
            pass  # killed while closing, after the session's end was written
        elif proc.returncode == 0 and outcome != "completed":
            out.problems.append(f"session {sid}: exit 0 but outcome {outcome}")
        elif proc.returncode == 3 and outcome not in ("fault", "paused", "journal", None):
            out.problems.append(f"session {sid}: exit 3 but outcome {outcome}")
        elif proc.returncode == 3 and outcome is None and not proc.disk_full:
            out.problems.append(f"session {sid}: exit 3 and no outcome, the disk was not full")
    for p in pauses:
        if not any("°C" in q or "supply" in q for q in p.data["problems"]):
            out.problems.append(f"pause event {p.id}: no injected overheat or sag explains it")
    ends = journal.samples["ended_s"].astype(np.float64)
    times = [e.t_s for e in journal.events]
    out.instrument_s = float(max(ends.max(initial=0.0), max(times, default=0.0)))
    out.paused_s = float(sum(e.data.get("paused_s", 0.0) for e in journal.of_kind("resume")))
    return out


def exactly_once(journal: Journal) -> list[str]:
    """Every target of the plan measured once or skipped (by policy), never both."""
    n = journal.targets
    measured = journal.samples["target"].astype(np.int64)
    skips = [e.target for e in journal.of_kind("skip") if e.target is not None]
    out = []
    if len(set(measured.tolist())) != len(measured):
        out.append("a target measured twice")
    if len(set(skips)) != len(skips):
        out.append("a target skipped twice")
    both = set(measured.tolist()) & set(skips)
    if both:
        out.append(f"targets both measured and skipped: {sorted(both)[:10]}")
    missing = set(range(n)) - set(measured.tolist()) - set(skips)
    if missing:
        out.append(f"{len(missing)} targets neither measured nor skipped: {sorted(missing)[:10]}")
    return out


@contextlib.contextmanager
def tmpfs(folder: Path, size_mb: int) -> Iterator[bool]:
    """A size-limited tmpfs mounted on ``folder`` for the block (root only); yields
    whether it was mounted (else ``folder`` is a plain folder)."""
    folder.mkdir(parents=True, exist_ok=True)
    mounted = False
    if os.geteuid() == 0:
        result = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size_mb}m", "soak", str(folder)],
            capture_output=True,
        )
        mounted = result.returncode == 0
    try:
        yield mounted
    finally:
        if mounted:
            subprocess.run(["umount", str(folder)], capture_output=True)
