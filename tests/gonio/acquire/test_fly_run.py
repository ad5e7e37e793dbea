"""Fly plans acquired on the simulated backend: sweep after sweep, each committed with its
raw streams in one transaction; the journaled streams merged again give the samples;
`kill -9` mid-sweep loses at most that sweep and the resumed run equals an uninterrupted
one bit for bit; a fault during a sweep journals it as abandoned (retried, or redone on
resume after a motor fault); a motor recovered by policy redoes it in the same
session."""

from __future__ import annotations

import json
import math
import random
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from drivers.devices import Devices
from drivers.values import StampedPositions
from gonio.acquire.fly import merge, run_sweep, target_slots
from gonio.acquire.recovery import MotorRecovery
from gonio.planner.policies import MotorFaultSpec
from gonio.store.journal import remove_run_file
from gonio.store.read import Run, open_run, raw_streams
from gonio.workflows import session
from tests.support.acquire import (
    ARCH,
    BRUSHED,
    PipeProgress,
    RunFiles,
    acquire_in_child,
    assert_same_samples,
    integrity,
    scene_yaml,
)


def fly_files(
    folder: Path,
    faults: list[dict[str, object]] | None = None,
    *,
    target: int = 700,
    seed: int = 1,
    fly: dict[str, object] | None = None,
) -> RunFiles:
    """A small fly plan on the arch rig and the brushed scene (with ``faults``); ``fly``:
    its fly options (default detector arcs at 0.5°)."""
    spec = {
        "name": "fly-small",
        "rig": str(ARCH),
        "parametrization": "rusinkiewicz",
        "isotropic": True,
        "sampling": {
            "strategy": "fly",
            "target": target,
            "seed": seed,
            "fly": fly or {"rate_hz": 100, "integration_s": 0.01, "blur_deg": 0.5},
        },
        "time_budget_s": 5,
        "acquisition": {
            "calibration": {"every_samples": 400, "averages": 4},
            "health": {"every_samples": 300},
            "on_fault": {"retries": 1, "then": "skip"},
        },
    }
    plan = folder / "fly.yaml"
    plan.write_text(yaml.safe_dump(spec, sort_keys=False))
    scene = folder / "scene.yaml"
    scene.write_text(scene_yaml(faults, BRUSHED))
    return RunFiles(plan, scene)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fly")


@pytest.fixture(scope="module")
def files(folder: Path) -> RunFiles:
    return fly_files(folder)


@pytest.fixture(scope="module")
def run(files: RunFiles, folder: Path) -> Run:
    out = folder / "run.sqlite"
    result = files.start(out)
    assert result.report.outcome == "completed", result.report.message
    return open_run(out)


def test_every_sweep_is_measured_and_its_targets_read(run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    assert [s.sweep for s in run.sweeps] == list(range(len(sweeps)))
    assert {s.outcome for s in run.sweeps} == {"measured"}
    assert len(run) + len(run.skipped) == len(run.plan)
    assert len(run) >= 0.95 * len(run.plan)
    # The detector streams every slot; the samples are the plan's targets only (the
    # thinning's other slots stay in the raw stream table).
    matched = sum(s.data["matched"] for s in run.sweeps)
    assert matched >= 0.95 * int(sweeps.streamed.sum()) and matched > len(run.plan)
    assert sum(s.data["kept"] for s in run.sweeps) == len(run)
    # The angles are the read ones, near the planned mid-window poses.
    gap = np.abs(run.angles("read_back") - run.angles("commanded")).max()
    speed = float(np.abs(sweeps.velocity).max())
    assert gap <= 0.5 * speed * sweeps.period_s + 1e-3
    # Smear: the path during one integration at the sweep's velocity.
    smear = run.samples["smear_rad"]
    # (polls interpolated between encoder ticks: within a few ticks of it)
    assert np.median(smear) == pytest.approx(speed * sweeps.integration_s, rel=0.05)
    assert np.all(
        np.abs(smear - speed * sweeps.integration_s) < 0.25 * speed * sweeps.integration_s
    )
    assert np.isfinite(run.samples["timing_rad"]).all() and (run.samples["timing_rad"] > 0).all()
    assert (run.samples["counts_std"] >= 0).all() and (run.samples["counts_std"] > 0).any()


def test_the_journaled_streams_merge_again_into_the_samples(run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    record = run.sweeps[1]
    times, positions, readings = raw_streams(run, record.id)
    assert len(readings) == record.data["readings"] and len(times) == record.data["polls"]
    slots = target_slots(sweeps, run.plan.arrival_s, record.sweep)
    matched = merge(
        times[:, 0], times[:, 1], positions, readings["started_s"], readings["ended_s"],
        sweeps, record.sweep, slots,
    )  # fmt: skip
    assert len(matched.index) == record.data["matched"]
    merged = matched.targets()
    assert len(merged.index) == record.data["kept"]
    rows = np.searchsorted(run.target, merged.target)
    np.testing.assert_array_equal(run.target[rows], merged.target)
    np.testing.assert_array_equal(run.angles("read_back")[rows], merged.angles)
    np.testing.assert_array_equal(run.samples["counts"][rows], readings["value"][merged.index])


def test_info_counts_the_sweeps_and_export_reads_the_run(
    run: Run, run_gonio: Any, tmp_path: Path
) -> None:
    result = run_gonio("info", str(run.path))
    assert result.returncode == 0, result.stderr
    sweeps = len(run.sweeps)
    assert f"sweeps measured: {sweeps} of {sweeps}" in result.stdout
    assert f"readings: {len(run)}" in result.stdout and "abandoned: 0" in result.stdout
    result = run_gonio("info", str(run.path), "--json")
    assert json.loads(result.stdout)["sweeps"] == {
        "planned": sweeps, "measured": sweeps, "abandoned": 0
    }  # fmt: skip
    out = tmp_path / "run.csv"
    result = run_gonio("export", str(run.path), "--format", "csv", "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    assert len(out.read_text().splitlines()) > len(run)


def slowed(devices: Devices, *args: Any, **kwargs: Any) -> Any:
    """`run_sweep` whose polls take a millisecond more of wall time each (not of virtual
    time), so a kill lands mid-sweep."""
    poll = devices.bus.poll_positions

    def slow_poll() -> StampedPositions:
        time.sleep(0.001)
        return poll()

    devices.bus.poll_positions = slow_poll  # type: ignore[method-assign]
    try:
        return run_sweep(devices, *args, **kwargs)
    finally:
        devices.bus.poll_positions = poll  # type: ignore[method-assign]


@pytest.mark.usefixtures("rigs_parsed_once")
def test_kill_9_mid_sweep_loses_at_most_that_sweep(
    files: RunFiles, run: Run, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("gonio.acquire.fly.loop.run_sweep", slowed)  # the children inherit it
    path = tmp_path / "run.sqlite"
    rng = random.Random(0)
    sweeps = run.plan.sweeps
    assert sweeps is not None
    for _ in range(2):
        remove_run_file(path)

        def start(progress: PipeProgress) -> session.SessionResult:
            return files.start(path, progress=progress)

        def resume(progress: PipeProgress) -> session.SessionResult:
            return session.resume(path, progress=progress)

        work, kills = start, 0
        while True:
            # Killed one to three sweeps in, plus a moment: counted in work
            # done, not in seconds, so a starved host still makes progress every time.
            child = acquire_in_child(
                work, kill_after=rng.randint(1, 3), delay_s=rng.uniform(0.0, 0.2)
            )
            assert integrity(path) == "ok"
            if not child.killed:
                assert child.last == "done completed", child.last
                break
            kills += 1
            partial = open_run(path)
            # Whole sweeps only: every journaled sweep has all its targets finished.
            finished = set(partial.target.tolist()) | set(partial.skipped.tolist())
            for s in partial.sweeps:
                first, count = int(sweeps.first[s.sweep]), int(sweeps.count[s.sweep])
                assert set(range(first, first + count)) <= finished
            assert len(finished) == sum(int(sweeps.count[s.sweep]) for s in partial.sweeps)
            work = resume
        assert kills >= 1
        assert_same_samples(open_run(path), run)


def test_a_fault_mid_sweep_abandons_the_sweep_and_redoes_it(tmp_path: Path, run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    first = int(sweeps.first[2])
    files = fly_files(tmp_path, faults=[{"kind": "comm_error", "at": [first]}])
    result = files.start(tmp_path / "run.sqlite")
    assert result.report.outcome == "completed", result.report.message
    faulted = open_run(tmp_path / "run.sqlite")
    outcomes = [(s.sweep, s.outcome) for s in faulted.sweeps]
    assert (2, "abandoned") in outcomes and (2, "measured") in outcomes
    assert len(faulted) + len(faulted.skipped) == len(faulted.plan)
    assert not math.isnan(float(faulted.samples["smear_rad"][0]))


def test_a_motor_fault_ends_the_run_resumable_and_the_resume_redoes_the_sweep(
    tmp_path: Path, run: Run
) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    first = int(sweeps.first[1])
    files = fly_files(tmp_path, faults=[{"kind": "motor_fault", "at": [first]}])
    path = tmp_path / "run.sqlite"
    result = files.start(path)
    assert result.report.outcome == "fault", result.report.message
    faulted = open_run(path)
    assert [(s.sweep, s.outcome) for s in faulted.sweeps] == [(0, "measured"), (1, "abandoned")]
    assert faulted.sweeps[1].data["error"] == "MotorFault"
    assert len(faulted) + len(faulted.skipped) == int(sweeps.count[0])
    resumed = session.resume(path)
    assert resumed.report.outcome == "completed", resumed.report.message
    done = open_run(path)
    assert [s.outcome for s in done.sweeps].count("measured") == len(sweeps)
    assert len(done) + len(done.skipped) == len(done.plan)


def test_a_motor_recovered_by_policy_redoes_the_sweep_in_the_same_session(
    tmp_path: Path, run: Run, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``on_fault.motor: recover`` (set on the engine here: the plan, and its ordering,
    stay the module's): the motor rebooted, the sweep measured again, the run done."""
    sweeps = run.plan.sweeps
    assert sweeps is not None
    first = int(sweeps.first[1])
    files = fly_files(tmp_path, faults=[{"kind": "motor_fault", "at": [first]}])
    made = MotorRecovery.of.__func__  # type: ignore[attr-defined]
    policy = MotorFaultSpec(action="recover")
    monkeypatch.setattr(
        MotorRecovery, "of", classmethod(lambda cls, _, *a, **k: made(cls, policy, *a, **k))
    )
    result = files.start(tmp_path / "run.sqlite")
    assert result.report.outcome == "completed", result.report.message
    done = result.run
    assert [(e.target, e.data["step"]) for e in done.of_kind("recovery")] == [
        (first, "diagnosed"), (first, "rebooted"), (first, "recovered"),
    ]  # fmt: skip
    assert [s.outcome for s in done.sweeps] == ["measured"] * len(sweeps)
    assert len(done) + len(done.skipped) == len(done.plan)


def test_a_sweep_that_kept_fewer_readings_is_redone(tmp_path: Path, run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    k = int(np.argmax(sweeps.count))  # the longest sweep: the gap takes some of its targets
    first = int(sweeps.first[k])
    files = fly_files(tmp_path, faults=[{"kind": "stream_gap", "at": [first]}])
    result = files.start(tmp_path / "run.sqlite")
    assert result.report.outcome == "completed", result.report.message
    gapped = open_run(tmp_path / "run.sqlite")
    mine = [s for s in gapped.sweeps if s.sweep == k]
    assert [s.outcome for s in mine] == ["abandoned", "measured"]
    short, measured = mine
    assert short.data["short"] is True and short.data["kept"] < short.data["count"]
    assert measured.data["kept"] == measured.data["count"] and measured.data["attempts"] == 2
    assert any(e.kind == "retry" and e.data.get("short") for e in gapped.events)
    assert len(gapped) == len(run) and not len(gapped.skipped)
