"""The acquisition engine on the simulated backend: every target measured and journaled
raw, the calibration schedule, drift and uncertainty through the calibration,
saturated readings measured again, targets outside the limits never commanded."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from gonio.analysis.calibrated import calibrate
from gonio.analysis.summary import truth_of
from gonio.store import open_run
from gonio.workflows import session
from tests.conftest import CliResult
from tests.support.acquire import acquire, build_plan, plan_file, scene_file


def test_every_target_is_measured_and_journaled_raw(tmp_path: Path) -> None:
    plan_path = plan_file(tmp_path, target=40)
    out = tmp_path / "run.sqlite"
    outcome = acquire(plan_path, scene_file(tmp_path), out)
    assert outcome.report.outcome == "completed" and outcome.report.measured == 40
    run = open_run(out)
    _, plan = build_plan(plan_path)
    assert run.plan == plan  # the stored plan is the plan, bit for bit
    np.testing.assert_array_equal(run.target, np.arange(40))
    np.testing.assert_array_equal(run.angles("commanded"), plan.angles)
    # Directions come from the read-back angles, through the rig's forward kinematics.
    wi, wo = plan.rig.forward(run.angles("read_back"))
    np.testing.assert_array_equal(run.directions()[0], wi)
    np.testing.assert_array_equal(run.directions()[1], wo)
    assert np.all(run.samples["counts"] > 0) and np.all(run.samples["n"] == 1)
    assert np.all(np.diff(run.samples["ended_s"]) > 0)
    kinds = [e.kind for e in run.events]
    assert kinds[0] == "start" and kinds.count("calibration") == 2 and run.complete
    assert (
        run.meta["hashes"]["plan_sha256"]
        == session.Files(plan_path, plan_path.read_bytes(), None, b"").hashes()["plan_sha256"]
    )


def test_the_calibration_schedule_reads_the_reference_every_n_targets(tmp_path: Path) -> None:
    plan_path = plan_file(
        tmp_path, target=40, acquisition="acquisition: {calibration: {every_samples: 15}}\n"
    )
    out = tmp_path / "run.sqlite"
    acquire(plan_path, scene_file(tmp_path), out)
    run = open_run(out)
    calibrations = run.of_kind("calibration")
    assert [c.data["count"] for c in calibrations] == [0, 15, 30, 40]
    assert [c.data["why"] for c in calibrations] == ["start", "scheduled", "scheduled", "end"]
    for c in calibrations:  # the reference and its dark, 16 exposures each, one exposure
        assert c.data["reference"]["n"] == 16 and c.data["dark"]["n"] == 16
        assert c.data["dark"]["value"] < 0.05 * c.data["reference"]["value"]
    ref_exposures = {c.data["reference"]["exposure_s"] for c in calibrations}
    assert len(ref_exposures) == 1


def test_drift_is_divided_out_between_the_reference_readings(tmp_path: Path) -> None:
    """A source drifting 50 % per hour, linearly: interpolating the reference readings in
    run time removes it to rounding (no noise effects)."""
    plan_path = plan_file(
        tmp_path, target=40, acquisition="acquisition: {calibration: {every_samples: 20}}\n"
    )
    scene = scene_file(tmp_path, "")
    text = scene.read_text(encoding="utf-8").replace(
        "effects: [shot_noise, read_noise, dark_current, quantization, saturation]",
        "effects: {source_drift: {rate_per_hour: 0.5}}",
    )
    scene.write_text(text, encoding="utf-8")
    out = tmp_path / "run.sqlite"
    acquire(plan_path, scene, out)
    run = open_run(out)
    cal = calibrate(run)
    rates = cal.series.rate
    assert rates[-1] / rates[0] - 1 > 0.005  # the source did drift (0.8 % over the run)
    np.testing.assert_allclose(cal.brdf, truth_of(run), rtol=1e-9)


def test_the_uncertainty_describes_the_scatter(tmp_path: Path) -> None:
    """With shot, read and dark noise, (f − truth)/σ scatters with unit spread."""
    plan_path = plan_file(tmp_path, target=300)
    out = tmp_path / "run.sqlite"
    acquire(plan_path, scene_file(tmp_path), out)
    run = open_run(out)
    cal = calibrate(run)
    z = (cal.brdf - truth_of(run)) / cal.sigma
    assert np.all(np.isfinite(z))
    # The reference reading's own error is common to every sample: remove that shift.
    assert 0.8 < float(np.std(z)) < 1.3
    assert np.median(cal.sigma / cal.brdf) < 0.01


def test_a_saturated_reading_is_measured_again_at_half_the_exposure(tmp_path: Path) -> None:
    faults = "faults:\n  - {kind: saturated, at: [3, 7]}\n"
    plan_path = plan_file(tmp_path, target=12)
    out = tmp_path / "run.sqlite"
    acquire(plan_path, scene_file(tmp_path, faults), out)
    s = open_run(out).samples
    assert s["remeasured"][3] == 1 and s["exposure_s"][3] == 0.025 and not s["saturated"][3]
    assert s["remeasured"][0] == 0 and s["exposure_s"][0] == 0.05
    off = plan_file(
        tmp_path,
        target=12,
        name="kept",
        acquisition="acquisition: {saturation: {remeasure: false}}\n",
    )
    out2 = tmp_path / "run2.sqlite"
    acquire(off, scene_file(tmp_path, faults), out2)
    s2 = open_run(out2).samples
    assert s2["saturated"][3] and s2["exposure_s"][3] == 0.05 and s2["remeasured"][3] == 0
    assert s2["counts"][3] == 65535.0  # kept, flagged


def test_a_target_outside_the_limits_is_skipped_never_commanded(tmp_path: Path) -> None:
    plan_path = plan_file(tmp_path, target=10)
    source, plan = build_plan(plan_path)
    angles = plan.angles.copy()
    angles[4, 0] = math.radians(86.0)  # the light arm stops at 85°
    angles[6, 1] = 1e3
    bad = dataclasses.replace(plan, angles=angles)
    files = session.Files(source.path, source.text, source.rig.source, source.rig.text)
    from gonio.scene import load_scene

    scene = load_scene(scene_file(tmp_path), source.rig)
    out = tmp_path / "run.sqlite"
    outcome = session.start(bad, files, scene=scene, output=out)
    assert outcome.report.outcome == "completed" and outcome.report.skipped == 2
    run = open_run(out)
    assert sorted(run.target.tolist()) == [0, 1, 2, 3, 5, 7, 8, 9]
    skips = {e.target: e.data["reason"] for e in run.of_kind("skip")}
    assert set(skips) == {4, 6}
    assert "'light_elevation'" in skips[4] and "outside its limits" in skips[4]
    assert "'detector_azimuth': 1000.0 rad is outside its limits" in skips[6]
    assert run.missing().size == 0 and run.missing(include_skipped=True).tolist() == [4, 6]


def test_a_plan_that_cannot_be_stored_is_refused_before_anything_moves(tmp_path: Path) -> None:
    plan_path = plan_file(tmp_path, target=5)
    source, plan = build_plan(plan_path)
    angles = plan.angles.copy()
    angles[2, 1] = math.nan
    files = session.Files(source.path, source.text, source.rig.source, source.rig.text)
    from gonio.scene import load_scene

    scene = load_scene(scene_file(tmp_path), source.rig)
    out = tmp_path / "run.sqlite"
    with pytest.raises(session.ConfigError, match="expected a finite number, got 'nan'"):
        session.start(dataclasses.replace(plan, angles=angles), files, scene=scene, output=out)
    assert not out.exists()


def test_gonio_info_reads_the_run(tmp_path: Path, run_gonio: object) -> None:
    plan_path = plan_file(tmp_path, target=10)
    out = tmp_path / "run.sqlite"
    acquire(plan_path, scene_file(tmp_path), out)
    r: CliResult = run_gonio("info", str(out), "--json")  # type: ignore[operator]
    assert r.returncode == 0, r.stderr
    figures = json.loads(r.stdout)
    assert figures["measured"] == 10 and figures["complete"] and figures["calibrations"] == 2
    assert figures["backend"] == "simulated" and figures["missing"] == 0
    r = run_gonio("info", str(out))  # type: ignore[operator]
    assert "targets measured                10   of 10 (0 skipped, 0 missing)" in r.stdout


def test_a_run_being_written_reads_as_a_consistent_snapshot(tmp_path: Path) -> None:
    """`open_run` while the writer is mid-run (it holds the file's lock) sees every
    sample committed so far and nothing half-written."""
    plan_path = plan_file(tmp_path, target=30)
    out = tmp_path / "run.sqlite"
    seen: list[tuple[int, int]] = []

    class Peek:
        def start(self, plan: object, todo: np.ndarray) -> None:
            pass

        def advance(self, done: int) -> None:
            if done % 7 == 0:
                seen.append((done, len(open_run(out))))

        def close(self) -> None:
            pass

    acquire(plan_path, scene_file(tmp_path), out, progress=Peek())
    assert seen == [(7, 7), (14, 14), (21, 21), (28, 28)]


@pytest.mark.parametrize("existing", [True, False])
def test_an_existing_run_file_is_never_replaced_silently(tmp_path: Path, existing: bool) -> None:
    plan_path = plan_file(tmp_path, target=5)
    out = tmp_path / "run.sqlite"
    if existing:
        out.write_bytes(b"precious")
        with pytest.raises(session.ConfigError, match="a run file already exists"):
            acquire(plan_path, scene_file(tmp_path), out)
        assert out.read_bytes() == b"precious"
    else:
        acquire(plan_path, scene_file(tmp_path), out)
        acquire(plan_path, scene_file(tmp_path), out, overwrite=True)
        assert len(open_run(out)) == 5 and len(open_run(out).sessions) == 1
