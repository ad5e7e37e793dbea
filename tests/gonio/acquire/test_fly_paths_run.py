"""Fly plans of θh lines (every axis following a trajectory) acquired on the simulated
backend: each path sweep followed, its targets read at their slots along the path, the
journaled streams merged again into the samples, `kill -9` mid-sweep resumed to the
uninterrupted run bit for bit, and the run evaluated and exported like any other."""

from __future__ import annotations

import random
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drivers.devices import Devices
from drivers.stream import StreamReading
from gonio.acquire.fly import merge_path, run_sweep, target_slots
from gonio.store.read import Run, open_run, raw_streams
from gonio.workflows import session
from tests.gonio.acquire.test_fly_run import fly_files
from tests.support.acquire import (
    RunFiles,
    acquire_in_child,
    assert_same_samples,
    integrity,
)


def path_files(folder: Path) -> RunFiles:
    lines = {"segment": "theta_h_line", "rate_hz": 100, "integration_s": 0.01, "blur_deg": 1.0}
    return fly_files(folder, target=900, seed=2, fly=lines)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("paths")


@pytest.fixture(scope="module")
def files(folder: Path) -> RunFiles:
    return path_files(folder)


@pytest.fixture(scope="module")
def run(files: RunFiles, folder: Path) -> Run:
    out = folder / "run.sqlite"
    result = files.start(out)
    assert result.report.outcome == "completed", result.report.message
    return open_run(out)


def test_every_path_sweep_is_followed_and_its_targets_read(run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None and sweeps.has_paths
    assert [(s.sweep, s.outcome) for s in run.sweeps] == [
        (k, "measured") for k in range(len(sweeps))
    ]
    assert len(run) == len(run.plan) and not len(run.skipped)
    # every axis moved along the path: the read-back angles are the planned ones (the
    # simulated bus follows the set-points exactly) up to where the stream's phase puts
    # each window, less than one reading period's travel
    gap = np.abs(run.angles("read_back") - run.angles("commanded"))
    steps = [np.abs(np.diff(sweeps.set_points(k), axis=0)) for k in range(len(sweeps))]
    speed = np.concatenate(steps).max(axis=0) / sweeps.path_period_s
    assert np.all(gap <= speed * sweeps.period_s + 1e-9)
    moved = np.ptp(run.angles("read_back"), axis=0)
    assert np.count_nonzero(moved > np.radians(5)) >= 3


def test_the_journaled_streams_merge_again_into_the_samples(run: Run) -> None:
    sweeps = run.plan.sweeps
    assert sweeps is not None
    record = run.sweeps[1]
    times, positions, readings = raw_streams(run, record.id)
    assert len(readings) == record.data["readings"] and len(times) == record.data["polls"]
    slots = target_slots(sweeps, run.plan.arrival_s, record.sweep)
    # the origin: the first reading's window starts at it, on the simulated clock
    origin = float(readings["started_s"][0])
    matched = merge_path(
        times[:, 0], times[:, 1], positions, readings["started_s"], readings["ended_s"],
        sweeps, record.sweep, origin, slots,
    )  # fmt: skip
    merged = matched.targets()
    assert len(merged.index) == record.data["kept"] == int(sweeps.count[record.sweep])
    rows = np.searchsorted(run.target, merged.target)
    np.testing.assert_array_equal(run.target[rows], merged.target)
    np.testing.assert_allclose(run.angles("read_back")[rows], merged.angles, atol=1e-12)
    np.testing.assert_array_equal(run.samples["counts"][rows], readings["value"][merged.index])


def test_evaluate_and_export_read_the_run(run: Run, run_gonio: Any, tmp_path: Path) -> None:
    for method in ("lines", "rbf"):
        result = run_gonio("evaluate", str(run.path), "--method", method)
        assert result.returncode == 0, result.stderr
        assert "log-RMSE" in result.stdout
    out = tmp_path / "run.h5"
    result = run_gonio("export", str(run.path), "--format", "hdf5", "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0


def slower(devices: Devices, *args: Any, **kwargs: Any) -> Any:
    """`run_sweep` whose stream reads take 10 ms more of wall time each (not of virtual
    time): a path sweep reads once a set-point, so it lasts about half a second."""
    detector: Any = devices.detector
    read = detector.read_stream

    def slow_read(timeout_s: float = 0.0) -> list[StreamReading]:
        time.sleep(0.01)
        return list(read(timeout_s))

    detector.read_stream = slow_read
    try:
        return run_sweep(devices, *args, **kwargs)
    finally:
        detector.read_stream = read


@pytest.mark.usefixtures("rigs_parsed_once")
def test_kill_9_mid_path_sweep_resumes_to_the_same_samples(
    files: RunFiles, run: Run, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("gonio.acquire.fly.loop.run_sweep", slower)  # the children inherit it
    path = tmp_path / "run.sqlite"
    sweeps = run.plan.sweeps
    assert sweeps is not None
    # killed once the first two sweeps are journaled (two reports), a little into the third
    two = int(sweeps.count[0] + sweeps.count[1])
    child = acquire_in_child(
        lambda progress: files.start(path, progress=progress),
        kill_after=2, delay_s=random.Random(1).uniform(0.05, 0.3),
    )  # fmt: skip
    assert child.killed and integrity(path) == "ok"
    partial = open_run(path)
    finished = set(partial.target.tolist()) | set(partial.skipped.tolist())
    assert len(finished) == sum(int(sweeps.count[s.sweep]) for s in partial.sweeps) >= two
    child = acquire_in_child(lambda progress: session.resume(path, progress=progress))
    assert not child.killed and child.last == "done completed", child.last
    assert_same_samples(open_run(path), run)


def mixed_files(folder: Path) -> RunFiles:
    lines = {"segment": "theta_h_line", "rate_hz": 100, "integration_s": 0.01,
             "blur_deg": 1.0, "fill": 30}  # fmt: skip
    return fly_files(folder, target=500, seed=3, fly=lines)


@pytest.mark.usefixtures("rigs_parsed_once")
def test_a_mixed_plan_reads_its_lines_then_its_fill_and_resumes_bit_for_bit(
    tmp_path: Path,
) -> None:
    files = mixed_files(tmp_path)
    whole = tmp_path / "whole.sqlite"
    result = files.start(whole)
    assert result.report.outcome == "completed", result.report.message
    run = open_run(whole)
    sweeps = run.plan.sweeps
    assert sweeps is not None and sweeps.swept == len(run.plan) - 30
    assert len(run) == len(run.plan) and not len(run.skipped)
    assert [s.outcome for s in run.sweeps] == ["measured"] * len(sweeps)
    # the fill: stop-and-go targets after the lines, at the plan's exposure, at rest
    fill = run.target >= sweeps.swept
    assert fill.sum() == 30
    exposure = run.samples["ended_s"][fill] - run.samples["started_s"][fill]
    np.testing.assert_allclose(exposure, run.plan.exposure_s[sweeps.swept :], rtol=0, atol=1e-9)
    gap = np.abs(run.angles("read_back") - run.angles("commanded"))[fill]
    assert gap.max() < np.radians(0.1)  # at rest: an encoder tick (the scene's position_error)
    # killed in the fill (after every sweep and five targets), resumed: the same samples
    path = tmp_path / "killed.sqlite"
    child = acquire_in_child(
        lambda progress: files.start(path, progress=progress),
        kill_after=len(sweeps) + 5, hold=True,
    )  # fmt: skip
    assert child.killed and integrity(path) == "ok"
    assert sweeps.swept < len(open_run(path)) < len(run.plan)
    child = acquire_in_child(lambda progress: session.resume(path, progress=progress))
    assert child.last == "done completed", child.last
    assert_same_samples(open_run(path), run)
