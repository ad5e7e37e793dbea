"""The plan's ``acquisition.on_fault.motor`` on the simulated backend: ``recover``
completes the run with every target measured once and each recovery step journaled
(and shown by `gonio info`), waits for a hot motor to cool on the run's clock, stops
resumable once a motor has been recovered ``max_recoveries`` times or when its position
after the reboot disagrees; ``stop`` ends the run with exit 3 as before; a Ctrl-C while
a motor cools pauses the run, the target in flight measured on resume."""

from __future__ import annotations

import json
import math
import os
import signal
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio.acquire import recovery
from gonio.acquire.recovery import describe, summaries
from gonio.acquire.signals import RunInterrupted
from gonio.config import ConfigError
from gonio.planner.files import load_plan_source
from gonio.store import UnjournaledValue
from gonio.store.journal import dumps
from gonio.store.read import Run, open_run
from gonio.workflows import session
from sim.clock import ManualClock
from tests.conftest import CliResult
from tests.support.acquire import RunFiles, plan_yaml

RECOVER = {"on_fault": {"motor": {"action": "recover", "max_recoveries": 2}}}


def steps(run: Run) -> list[tuple[int | None, str, str]]:
    return [(e.target, e.data["axis"], e.data["step"]) for e in run.of_kind("recovery")]


def measured_once(run: Run) -> None:
    assert run.complete and len(run) == len(run.plan)
    assert sorted(run.target.tolist()) == list(range(len(run.plan)))  # once each


def test_recover_measures_every_target_once_and_journals_each_step(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    files = run_files(20, acquisition=RECOVER, faults=[
        {"kind": "motor_fault", "at": [5], "axis": "detector_elevation"},
        {"kind": "motor_fault", "at": [9, 14], "axis": "light_elevation",
         "flags": ["overheating"], "temperature_c": 78, "for_s": 120},
    ])  # fmt: skip
    path = tmp_path / "run.sqlite"
    outcome = files.start(path)
    assert outcome.report.outcome == "completed", outcome.report
    run = outcome.run
    measured_once(run)
    assert not run.of_kind("fault")
    assert steps(run) == [
        (5, "detector_elevation", "diagnosed"),
        (5, "detector_elevation", "rebooted"),
        (5, "detector_elevation", "recovered"),
        *[
            (t, "light_elevation", s)
            for t in (9, 14)
            for s in ("diagnosed", "cooling", "cooled", "rebooted", "recovered")
        ],
    ]
    events = run.of_kind("recovery")
    diagnosed = events[0].data
    assert diagnosed["flags"] == ["overload"] and diagnosed["recovery"] == 1
    assert diagnosed["temperature_c"] == 35.0 and diagnosed["motor_id"] == 3
    cooling, cooled = (e for e in events[3:8] if e.data["step"] in ("cooling", "cooled"))
    assert cooling.data["temperature_c"] == 78 and cooling.data["below_c"] == 65.0
    # On the run's clock: polled every health.poll_s (10 s) until 120 s after the fault.
    waited = cooled.data["waited_s"]
    assert 120 <= waited <= 130 and cooled.t_s - cooling.t_s == waited
    assert cooled.data["temperature_c"] < 65
    assert [e.data["recovery"] for e in events if e.data["step"] == "rebooted"] == [1, 1, 2]
    assert all(e.data["deviation_deg"] == 0.0 for e in events if e.data["step"] == "rebooted")
    attempts = dict(zip(run.target.tolist(), run.samples["attempts"].tolist(), strict=True))
    assert attempts[4] == 1 and attempts[5] == 1  # measured again, not a transient retry

    result = run_gonio("info", str(path))
    assert result.returncode == 0
    lines = [line for line in result.stdout.splitlines() if "recovery" in line]
    assert lines == describe(run)[1:] and len(lines) == 3
    assert lines[0] == (
        "    recovery 1 of detector_elevation (motor 3) at target 5: overload (35 °C); "
        "rebooted, 0° from its hold; measured again"
    )
    assert "cooled 1" in lines[1] and "motor recoveries" in result.stdout
    figures = json.loads(run_gonio("info", str(path), "--json").stdout)
    assert figures["recoveries"] == json.loads(json.dumps(summaries(run)))


def test_stop_ends_the_run_with_exit_3_as_before(
    tmp_path: Path, run_files: Callable[..., RunFiles], run_gonio: Callable[..., CliResult]
) -> None:
    files = run_files(20, faults=[{"kind": "motor_fault", "at": [5]}])  # the default: stop
    path = tmp_path / "run.sqlite"
    assert run_gonio(*files.cli(path)).returncode == 3
    assert not (info := run_gonio("info", str(path))).returncode
    assert "recovery" not in info.stdout


def ended_by_fault(files: RunFiles, path: Path, measured: int) -> Run:
    outcome = files.start(path)
    assert outcome.report.outcome == "fault", outcome.report
    run = outcome.run
    assert len(run) == measured and run.sessions[-1].outcome == "fault"
    return run


def test_more_recoveries_than_allowed_stop_resumable(
    tmp_path: Path, run_files: Callable[..., RunFiles]
) -> None:
    files = run_files(
        20,
        acquisition=RECOVER,
        faults=[
            {"kind": "motor_fault", "at": [3, 7, 12, 15], "axis": "detector_azimuth"},
        ],
    )
    path = tmp_path / "run.sqlite"
    run = ended_by_fault(files, path, 12)
    assert [s for t, _, s in steps(run) if t == 12] == ["diagnosed", "failed"]
    (fault,) = run.of_kind("fault")
    assert fault.target == 12 and "not recovered: rebooted 2 times" in fault.data["message"]
    assert summaries(run)[-1]["outcome"] == "failed"
    # Per run: a resumed session counts the reboots its journal holds.
    again = session.resume(path)
    assert again.report.outcome == "fault" and len(again.run) == 15
    assert [s for t, _, s in steps(again.run) if t == 15] == ["diagnosed", "failed"]
    assert session.resume(path).report.outcome == "completed"


def test_a_position_that_disagrees_after_the_reboot_stops(
    tmp_path: Path, run_files: Callable[..., RunFiles]
) -> None:
    files = run_files(
        20,
        acquisition=RECOVER,
        faults=[
            {"kind": "motor_fault", "at": [6], "axis": "sample_rotation", "shift_deg": 180.0},
        ],
    )
    run = ended_by_fault(files, tmp_path / "run.sqlite", 6)
    rebooted, failed = (e.data for e in run.of_kind("recovery")[1:])
    assert rebooted["step"] == "rebooted" and failed["step"] == "failed"
    assert np.isclose(rebooted["deviation_deg"], 180.0) and rebooted["tolerance_deg"] == 0.5
    assert "re-home it" in failed["reason"]
    (fault,) = run.of_kind("fault")
    assert fault.data["axis"] == "sample_rotation" and fault.data["flags"] == ["overload"]


def test_a_motor_that_does_not_cool_in_time_stops(
    tmp_path: Path, run_files: Callable[..., RunFiles]
) -> None:
    acquisition: dict[str, Any] = {
        "on_fault": {"motor": {"action": "recover", "cool_down_minutes": 1}}
    }
    files = run_files(
        20,
        acquisition=acquisition,
        faults=[
            {
                "kind": "motor_fault",
                "at": [4],
                "axis": "light_elevation",
                "flags": ["overheating"],
                "for_s": 600,
            },
        ],
    )
    run = ended_by_fault(files, tmp_path / "run.sqlite", 4)
    assert [s for _, _, s in steps(run)] == ["diagnosed", "cooling", "failed"]
    assert "still 80 °C after 1 min" in run.of_kind("recovery")[-1].data["reason"]


def test_ctrl_c_while_a_motor_cools_pauses_and_the_resume_measures_the_target(
    tmp_path: Path, run_files: Callable[..., RunFiles], monkeypatch: pytest.MonkeyPatch
) -> None:
    files = run_files(
        12,
        acquisition=RECOVER,
        faults=[
            {"kind": "motor_fault", "at": [4], "axis": "light_elevation", "flags": ["overheating"]},
        ],
    )
    sleep = ManualClock.sleep

    def ctrl_c_while_cooling(clock: ManualClock, seconds: float) -> None:
        if seconds == 10.0:  # the cooling's poll (settling is 0.2 s)
            os.kill(os.getpid(), signal.SIGINT)
        sleep(clock, seconds)

    monkeypatch.setattr(ManualClock, "sleep", ctrl_c_while_cooling)
    path = tmp_path / "run.sqlite"
    with pytest.raises(RunInterrupted):
        files.start(path)
    monkeypatch.setattr(ManualClock, "sleep", sleep)
    run = open_run(path)
    assert len(run) == 4 and run.sessions[-1].outcome == "interrupted"
    assert [s for _, _, s in steps(run)] == ["diagnosed", "cooling"]
    (pause,) = run.of_kind("pause")
    assert pause.data["abandoned"] is True
    measured_once(session.resume(path).run)


def test_an_electrical_shock_is_never_recovered(
    tmp_path: Path, run_files: Callable[..., RunFiles]
) -> None:
    files = run_files(
        12,
        acquisition=RECOVER,
        faults=[
            {
                "kind": "motor_fault",
                "at": [5],
                "axis": "detector_azimuth",
                "flags": ["electrical_shock"],
            },
        ],
    )
    run = ended_by_fault(files, tmp_path / "run.sqlite", 5)
    assert [s for _, _, s in steps(run)] == ["diagnosed", "failed"]
    assert "never recovered unattended" in run.of_kind("recovery")[-1].data["reason"]


@pytest.mark.parametrize(
    ("policy", "expected"),
    [
        (
            {"on_fault": {"motor": {"cool_down_minutes": "1e308"}}},
            "on_fault.motor.cool_down_minutes",
        ),
        ({"on_fault": {"motor": {"cool_down_minutes": 1e308}}}, "on_fault.motor.cool_down_minutes"),
        ({"health": {"pause_timeout_minutes": 1e300}}, "health.pause_timeout_minutes"),
        ({"health": {"every_minutes": 1e300}}, "health.every_minutes"),
        ({"health": {"poll_s": 1e-300}}, "health.poll_s"),
        ({"health": {"every_samples": 10**15}}, "health.every_samples"),
        ({"calibration": {"every_minutes": 1e300}}, "calibration.every_minutes"),
        ({"calibration": {"every_samples": 10**15}}, "calibration.every_samples"),
    ],
)
def test_an_absurd_policy_number_is_refused_at_load(
    tmp_path: Path, policy: dict[str, Any], expected: str
) -> None:
    path = tmp_path / "plan.yaml"
    path.write_text(plan_yaml(acquisition=policy))
    with pytest.raises(ConfigError) as caught:
        load_plan_source(path)
    message = str(caught.value)
    assert (
        message.startswith(f"{path}:") and f": acquisition.{expected}: Input should be" in message
    )
    assert "\n" not in message


def test_a_value_the_journal_cannot_store_ends_the_run_aborted_and_ended(
    tmp_path: Path, run_files: Callable[..., RunFiles], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Defence in depth: an event value no configuration bound caught (an infinity) ends
    the session ``aborted`` with a message naming it, never a run left not ended."""
    files = run_files(
        12,
        acquisition=RECOVER,
        faults=[
            {"kind": "motor_fault", "at": [4], "axis": "light_elevation", "flags": ["overheating"]},
        ],
    )
    monkeypatch.setattr(recovery, "_condition", lambda health: {"temperature_c": math.inf})
    path = tmp_path / "run.sqlite"
    outcome = files.start(path)
    assert outcome.report.outcome == "aborted"
    assert outcome.report.message.startswith("cannot journal temperature_c = inf: ")
    assert open_run(path).sessions[-1].outcome == "aborted"


def test_the_journal_refuses_a_non_finite_number_naming_where() -> None:
    with pytest.raises(UnjournaledValue, match=r"cannot journal a\.1\.b = nan: "):
        dumps({"a": [1.0, {"b": math.nan}]})
    assert dumps({"a": [1e308, -0.0]}) == '{"a":[1e+308,-0.0]}'
