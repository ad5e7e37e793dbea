"""The soak, shortened: a simulated run of 1 200 targets with a fault of every class
injected at chosen samples (a lost status packet, two corrupt ones in a row, a burst
of five lost ones that outlasts the retries, a detector timeout and a burst of them, a
saturated reading, a motor overload and overheating, a motion timeout, an overheat and
a supply sag of hours), its ``gonio acquire`` killed with SIGKILL three times and its
disk filled once, resumed until it completes: every target measured exactly once or
skipped by policy, the run file sound after every session, every fault matched with its
handling event and every session with its process, and the samples equal to those of
the same run uninterrupted, bit for bit. benchmarks/soak.py runs it at full scale."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from gonio.cli import main, render, run_table
from gonio.planner import files
from gonio.workflows import session
from tests.soak import (
    CALIBRATION_INDEX,
    ForkLauncher,
    Journal,
    KillSchedule,
    exactly_once,
    run_soak,
    same_samples,
    story,
    write_files,
)

TARGETS = 1200
FAULTS: list[dict[str, Any]] = [
    {"kind": "comm_error", "packet": "lost", "at": [50]},
    {"kind": "comm_error", "packet": "corrupt", "burst": 2, "at": [120]},
    {"kind": "comm_error", "packet": "lost", "burst": 5, "at": [180]},
    {"kind": "detector_error", "at": [260]},
    {"kind": "detector_error", "burst": 4, "at": [330]},
    {"kind": "saturated", "at": [400, 401]},
    {"kind": "motor_fault", "at": [470], "axis": "detector_elevation", "flags": ["overload"]},
    {"kind": "motor_fault", "at": [620], "axis": "light_elevation", "flags": ["overheating"]},
    {"kind": "motion_timeout", "at": [700]},
    {"kind": "overheat", "at": [800], "axis": "detector_azimuth", "temperature_c": 74,
     "for_s": 5400},
    {"kind": "supply_sag", "at": [950], "voltage_v": 9.2, "for_s": 3 * 3600},
]  # fmt: skip
#: The pause gives up after 2 h: the 3 h sag ends its session (resumable) once.
ACQUISITION = {
    "calibration": {"every_minutes": 30, "averages": 4},
    "on_fault": {"retries": 2, "then": "skip"},
    "health": {"every_samples": 50, "every_minutes": 5, "poll_s": 60,
               "pause_timeout_minutes": 120},
}  # fmt: skip


#: What `gonio acquire` imports when it runs, imported here once: each forked session
#: then starts at once.
PRELOADED = (render, run_table, files, session)


def test_a_short_soak(tmp_path: Path) -> None:
    launch = ForkLauncher(main)
    soak = write_files(tmp_path / "soak", tmp_path / "soak" / "run.sqlite", TARGETS, 11, FAULTS,
                       ACQUISITION)  # fmt: skip
    schedule = KillSchedule(2, 3, TARGETS // 3, disk_full=1, startup_s=0.3, disk_room=128 << 10)
    lines: list[str] = []
    run_soak(soak, schedule, launch=launch, say=lines.append)
    print("\n".join(lines))
    assert soak.problems == []
    assert soak.kills == 3
    assert all(s.integrity == "ok" for s in soak.sessions if s.integrity)
    full = [s for s in soak.sessions if s.disk_full]
    assert len(full) == 1 and full[0].returncode == 3
    assert "cannot write the journal" in full[0].stderr

    journal = Journal.read(soak.run)
    assert exactly_once(journal) == []
    told = story(soak, journal)
    assert told.problems == []
    handled = {name: (struck, done) for name, (struck, done, _) in told.classes.items()}
    assert handled == {
        "status packet lost": (1, 1),
        "status packet corrupt, bursts of 2": (1, 1),
        "status packet lost, bursts of 5": (1, 1),
        "detector timeout": (1, 1),
        "detector timeout, bursts of 4": (1, 1),
        "saturated": (2, 2),
        "motor overload": (1, 1),
        "motor overheating": (1, 1),
        "motion timeout": (1, 1),
        "overheat (1.5 h)": (1, 1),
        "supply sag (3 h)": (1, 1),
    }
    assert "skipped by policy" in told.classes["status packet lost, bursts of 5"][2]
    assert "skipped by policy" in told.classes["detector timeout, bursts of 4"][2]
    assert told.outcomes["paused"] >= 1 and told.outcomes["fault"] >= 3
    assert told.instrument_s > 4 * 3600  # hours of instrument time

    reference = write_files(tmp_path / "ref", tmp_path / "ref" / "run.sqlite", TARGETS, 11,
                            FAULTS, ACQUISITION)  # fmt: skip
    run_soak(reference, None, launch=launch)
    assert reference.problems == [] and reference.kills == 0
    assert same_samples(journal, Journal.read(reference.run)) == []


def test_a_transient_fault_in_a_calibration_is_retried(tmp_path: Path) -> None:
    """A lost status packet and a detector timeout in calibrations are retried (a
    ``retry`` event naming the calibration); a burst longer than the retries ends the
    session resumable, and the resume takes the calibration again."""
    cal = CALIBRATION_INDEX
    faults = [
        {"kind": "comm_error", "at": [cal + 2]},  # the second calibration's reference
        {"kind": "detector_error", "at": [cal + 5]},  # the third's dark
        {"kind": "comm_error", "burst": 4, "at": [cal + 6]},  # the last's reference
    ]
    acquisition = {"calibration": {"every_samples": 20, "averages": 4},
                   "on_fault": {"retries": 2}, "health": {"every_samples": 10}}  # fmt: skip
    soak = write_files(tmp_path, tmp_path / "run.sqlite", 60, 3, faults, acquisition)
    run_soak(soak, None, launch=ForkLauncher(main))
    assert soak.problems == []
    assert [s.returncode for s in soak.sessions] == [3, 0]
    journal = Journal.read(soak.run)
    retries = [(e.data["error"], e.data["calibration"]) for e in journal.of_kind("retry")]
    assert retries == [
        ("CommError", "scheduled"),
        ("DetectorError", "scheduled"),
        ("CommError", "end"),
        ("CommError", "end"),
        ("CommError", "end"),
    ]
    assert [e.target for e in journal.of_kind("fault")] == [None]
    assert len(journal.of_kind("calibration")) == 4
    assert story(soak, journal).problems == []
