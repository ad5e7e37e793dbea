"""The soak: days of instrument time unattended, in virtual time, with every fault
class injected, the acquiring process killed with SIGKILL at random moments and the
disk filling up.

A simulated run of 100 000 targets (a Sobol plan on the arch rig, 0.5 s × 4 exposures
each, brushed metal with noise, drift, backlash and repeatability) is acquired by
``python -m gonio acquire``, a real process, resumed with ``gonio acquire --resume``
after every session until it completes (`tests.soak`). Faults are injected by the scene
at rates per sample of the order users report (`tests.soak.realistic_faults`): lost status
packets and corrupt ones (in bursts, one longer than the plan's two retries), detector
timeouts (one burst longer than the retries), saturated readings, motor overload and
overheating (a hardware error: today's policy stops the run resumable, and the loop
resumes it), motion timeouts, an overheat of 2.5 h and a supply sag of 5 h (health
pauses: the plan gives up a pause after 4 h, resumable) and supply sags of 10 min. A
seeded schedule SIGKILLs the process 50 times (a quarter at any moment of a session's
start, the rest a few milliseconds after some new samples were committed) and fills the
disk twice: the run file lives on a size-limited tmpfs (when the script runs as root;
else a file-size limit on the process stands in) that a filler file leaves 4 MB free,
removed before the next session.

Checked after every session: ``PRAGMA integrity_check`` and that no finished target
was lost. At the end: every target measured exactly once or skipped by policy; every
injected fault (recomputed from the rules with the simulator's own injector) has its
handling event in the journal and every retry, skip and fault event its injected
fault; every session ends as its process did and every session after the first begins
with a resume that counts the targets left right; and the samples, calibrations and
skips equal, bit for bit, those of the same run acquired without kills or full disks.

Run: nice .venv/bin/python benchmarks/soak.py [--targets N] [--kills K] [--seed S]
"""

from __future__ import annotations

import argparse
import itertools
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report

from gonio.rig import Rig
from gonio.scene import load_scene
from tests.soak import (
    ROOT,
    Journal,
    KillSchedule,
    Soak,
    Story,
    exactly_once,
    finished,
    realistic_faults,
    run_soak,
    same_samples,
    story,
    tmpfs,
    write_files,
)
from tests.soak.rehearsal import ARCH_SERIAL, RehearsalSoak, read_events, run_rehearsal_soak


def hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h ({seconds / 86400:.2f} days)"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", type=int, default=100_000)
    parser.add_argument("--kills", type=int, default=50)
    parser.add_argument("--disk-full", type=int, default=2)
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--rehearsal-targets", type=int, default=300)
    parser.add_argument("--rehearsal-kills", type=int, default=6)
    args = parser.parse_args(argv)
    n = args.targets

    def say(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    with tempfile.TemporaryDirectory(prefix="gonio-soak-") as tmp:
        folder = Path(tmp)
        faults = realistic_faults(n)
        with tmpfs(folder / "disk", 512) as mounted:
            soak = write_files(
                folder / "soak", folder / "disk" / "run.sqlite", n, args.seed, faults
            )
            schedule = KillSchedule(args.seed, args.kills, n, disk_full=args.disk_full)
            say(f"soak: {n} targets, {args.kills} kills, disk {'tmpfs' if mounted else 'rlimit'}")
            run_soak(soak, schedule, disk="tmpfs" if mounted else "rlimit", say=say)
            journal = Journal.read(soak.run)
        say("the same run, uninterrupted")
        reference = write_files(folder / "ref", folder / "ref" / "run.sqlite", n, args.seed, faults)
        run_soak(reference, None, say=say)
        started = time.monotonic()
        told = story(soak, journal)
        once = exactly_once(journal)
        differ = same_samples(journal, Journal.read(reference.run))
        check_s = time.monotonic() - started
        report(soak, reference, journal, told, once, differ, mounted, check_s)
        if args.rehearsal_targets:
            say("the rehearsal path")
            rig = Rig.from_yaml(ARCH_SERIAL)
            scene = load_scene(ROOT / "configs" / "scenes" / "matte.yaml", rig)
            rehearsal = run_rehearsal_soak(
                folder / "rehearsal",
                args.rehearsal_targets,
                args.rehearsal_kills,
                args.seed,
                scene,
                say=say,
            )
            report_rehearsal(rehearsal)


def report_rehearsal(soak: RehearsalSoak) -> None:
    sessions = soak.sessions
    print("\n## The hardware path: real drivers, emulated devices\n")
    print(
        "`DynamixelBus`, `SerialDetector` and `SerialLightSwitch` in the killed process; "
        "the Dynamixel emulator (4 motors, 50 × real time), the photometer and the lamp "
        "relay on ptys in the soak's process, so what a kill leaves can be looked at.\n"
    )
    events = read_events(soak.run) if soak.run.exists() else {}
    checked = [s for s in sessions if s.integrity]
    measured, skipped = finished(soak.run) if soak.run.exists() else ([], [])
    rows = [
        ("targets in the plan", f"{soak.targets}"),
        ("targets measured / skipped", f"{len(measured)} / {len(skipped)}"),
        ("wall time", f"{soak.wall_s:.0f} s"),
        ("sessions (processes started)", f"{len(sessions)}"),
        ("SIGKILLs survived", f"{soak.kills}"),
        (
            "integrity_check ok after a session",
            f"{sum(s.integrity == 'ok' for s in checked)} of {len(checked)}",
        ),
        (
            "after a kill: every motor's torque on",
            f"{sum(a.torque_on for a in soak.after_kills)} of {len(soak.after_kills)}",
        ),
        (
            "after a kill: every motor still, at its goal",
            f"{sum(a.held for a in soak.after_kills)} of {len(soak.after_kills)}",
        ),
        (
            "after a kill: every port released",
            f"{sum(a.ports_free for a in soak.after_kills)} of {len(soak.after_kills)}",
        ),
        ("motor reboots (`gonio motors reboot`, as an operator)", f"{soak.reboots}"),
    ]
    print("| figure | value |")
    print("|---|---:|")
    for label, value in rows:
        print(f"| {label} | {value} |")
    print("\n| injected into the emulator | count |")
    print("|---|---:|")
    for name, count in sorted(soak.injected.items()):
        print(f"| {name} | {count} |")
    print("\n| event kind | events |")
    print("|---|---:|")
    for kind, count in sorted(events.items(), key=lambda kv: -kv[1]):
        print(f"| {kind} | {count} |")
    print(
        "\nsessions: "
        + ", ".join("killed" if s.killed else f"exit {s.returncode}" for s in sessions)
    )
    for a in soak.after_kills:
        if a.detail:
            print(f"- after the kill of session {a.session}: {a.detail}")
    for problem in soak.problems:
        print(f"- PROBLEM: {problem}")


def report(
    soak: Soak,
    reference: Soak,
    journal: Journal,
    told: Story,
    once: list[str],
    differ: list[str],
    mounted: bool,
    check_s: float,
) -> None:
    sessions = soak.sessions
    full = [s for s in sessions if s.disk_full]
    checked = [s for s in sessions if s.integrity]
    kills = soak.kills
    resumed_after_kill = sum(
        1 for a, b in itertools.pairwise(sessions) if a.killed and b.argv[1] == "--resume"
    )
    disk = (
        "a 512 MB tmpfs, filled by a filler file to 4 MB free (ENOSPC)"
        if mounted
        else "a file-size limit on the process (RLIMIT_FSIZE: EFBIG)"
    )
    print("## The run\n")
    print("| figure | value |")
    print("|---|---:|")
    rows = [
        ("targets in the plan", f"{journal.targets:,}"),
        ("instrument time covered (virtual)", hours(told.instrument_s)),
        ("of which in health pauses (resumed)", hours(told.paused_s)),
        ("wall time of the soak (sessions and their checks)", f"{soak.wall_s:.0f} s"),
        ("wall time of the uninterrupted run", f"{reference.wall_s:.0f} s"),
        ("sessions (processes started)", f"{len(sessions)}"),
        ("SIGKILLs survived", f"{kills}"),
        ("of which resumed by the next session", f"{resumed_after_kill}"),
        ("full disks survived", f"{sum(s.returncode == 3 for s in full)} of {len(full)}"),
        ("sessions ended resumable (exit 3)", f"{sum(s.returncode == 3 for s in sessions)}"),
        (
            "integrity_check ok after a session",
            f"{sum(s.integrity == 'ok' for s in checked)} of {len(checked)}",
        ),
        ("samples journaled", f"{len(journal.samples['target']):,}"),
        ("targets skipped by policy", f"{told.counts['skip']}"),
    ]
    for label, value in rows:
        print(f"| {label} | {value} |")
    print(f"\nthe full disk: {disk}")
    for s in full:
        last = s.stderr.strip().splitlines()[0] if s.stderr.strip() else "(nothing)"
        print(f"- session {s.number}: exit {s.returncode}: {last}")
    print("\n## Faults by class and how each was handled\n")
    print("| fault class | struck | handled | how (from the journal's events) |")
    print("|---|---:|---:|---|")
    for name, (struck, handled, how) in told.classes.items():
        print(f"| {name} | {struck} | {handled} | {how} |")
    print("\n## Sessions by how the journal says they ended\n")
    print("| outcome | sessions |")
    print("|---|---:|")
    for outcome, count in told.outcomes.most_common():
        print(f"| {outcome} | {count} |")
    print("\n## Events journaled\n")
    print("| kind | events |")
    print("|---|---:|")
    for kind, count in told.counts.most_common():
        print(f"| {kind} | {count:,} |")
    print("\n## Checks\n")
    checks = [
        ("every target measured exactly once or skipped by policy", not once, once),
        (
            "integrity_check ok after every session",
            all(s.integrity == "ok" for s in checked),
            [s.integrity for s in checked if s.integrity != "ok"],
        ),
        ("no finished target lost by a kill or a full disk", not soak.problems, soak.problems),
        (
            "the journal tells the whole story (faults ↔ events, sessions ↔ processes)",
            not told.problems,
            told.problems,
        ),
        (
            "samples, calibrations and skips equal the uninterrupted run's, bit for bit",
            not differ,
            differ,
        ),
    ]
    print("| check | result |")
    print("|---|---|")
    for label, ok, problems in checks:
        detail = "" if ok else f" ({len(problems)}: {'; '.join(map(str, problems[:3]))})"
        print(f"| {label} | {'ok' if ok else 'FAILED'}{detail} |")
    print(f"\nthe checks at the end took {check_s:.1f} s")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The soak: days unattended in virtual time")
