"""`gonio align`'s fly scans on the simulated backend, against its stop-and-go scans of
the same misaligned mirror: both recover every determined parameter within 0.03°, the
fly scan in well under half the instrument time (the simulated clock's, from the
readings' own windows); a timing latency shifts each way of a fine sweep and the two
ways' mean cancels it; a detector that cannot stream scans stop-and-go; on the
rehearsal path at real speed the fly scan lands where the stop-and-go one does."""

from __future__ import annotations

import contextlib
import io
import math
import sqlite3
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.cli import main
from gonio.rig import Rig
from gonio.rig.alignment_file import load_alignment
from gonio.scene import load_scene
from gonio.workflows import align, backends
from tests.conftest import CONFIGS
from tests.gonio.cli.test_align import ARCH, TRUTH, mirror_scene


def _align(folder: Path, *options: str) -> tuple[Path, str]:
    """(sidecar, stdout) of ``gonio align`` on a copy of the arch rig in ``folder``."""
    rig = folder / "arch.yaml"
    rig.write_bytes(ARCH.read_bytes())
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["align", str(rig), "--scene", str(mirror_scene(folder, TRUTH)), *options])
    assert code == 0
    return rig.with_name("arch.alignment.scan.sqlite"), out.getvalue()


@pytest.fixture(scope="module")
def stop_and_go(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    return _align(tmp_path_factory.mktemp("stop_and_go"), "--stop-and-go")


@pytest.fixture(scope="module")
def flown(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    return _align(tmp_path_factory.mktemp("fly"))


def _recovered(sidecar: Path) -> dict[str, float]:
    """Each checked quantity's error (°) against `TRUTH` in the alignment file."""
    file = load_alignment(sidecar.with_name("arch.alignment.yaml"))
    assert file.fit is not None
    d = {name: p.value for name, p in file.fit.parameters.items()}
    s = file.alignment
    azimuth = math.radians(40.0 + 0.3)  # the tilt's azimuth as read
    return {
        "zero_offset.detector_azimuth": d["zero_offset.detector_azimuth"] + 0.4,
        "tilt_x": d["tilt_x"] - 0.5 * math.cos(azimuth),
        "tilt_y": d["tilt_y"] - 0.5 * math.sin(azimuth),
        "light_pointing_x": d["light_pointing_x"] - 0.3,
        "light": s.zero_offset_deg["light_elevation"] + s.light_pointing_deg[1] - 0.5,
        "detector": s.zero_offset_deg["detector_elevation"] + s.detector_pointing_deg[1] - 0.8,
    }


def _modes_and_span(sidecar: Path) -> tuple[set[str], float]:
    """The modes the readings name and their span on the instrument's clock (s)."""
    with contextlib.closing(sqlite3.connect(sidecar)) as db:
        modes = {m for (m,) in db.execute("SELECT DISTINCT mode FROM reading")}
        (span,) = db.execute("SELECT MAX(ended_s) - MIN(started_s) FROM reading").fetchone()
    return modes, float(span)


def test_a_fly_align_recovers_the_truth_in_less_instrument_time(
    flown: tuple[Path, str], stop_and_go: tuple[Path, str]
) -> None:
    (fly_file, fly_out), (sag_file, sag_out) = flown, stop_and_go
    for sidecar in (fly_file, sag_file):
        errors = _recovered(sidecar)
        assert max(abs(e) for e in errors.values()) <= 0.03, errors
    fly_modes, fly_s = _modes_and_span(fly_file)
    sag_modes, sag_s = _modes_and_span(sag_file)
    assert fly_modes == {"fly"} and sag_modes == {"stop_and_go"}
    assert "(fly scans)" in fly_out and "(stop-and-go)" in sag_out
    # the simulated clock: the readings' own windows, first to last
    assert fly_s < 0.5 * sag_s and fly_s <= 180.0, (fly_s, sag_s)


def test_the_fine_sweeps_both_ways_cancel_a_timing_latency(tmp_path: Path) -> None:
    """A detector stamping its windows 2 ms late shifts each way's peak by about
    velocity × latency, in opposite directions; the mean of the two ways is where a
    latency-free scan puts it."""
    rig = Rig.from_yaml(ARCH)
    settings = align.ScanSettings()
    center = align.nominal_poses(rig, settings)[0]
    peaks = {}
    for latency in (0.0, 2e-3):
        data = yaml.safe_load(mirror_scene(tmp_path, TRUTH).read_text())
        data["effects"]["timestamp_jitter"] = {"sigma_s": 0.0, "latency_s": latency}
        (tmp_path / "late.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
        scene = load_scene(tmp_path / "late.yaml", rig)
        backend = backends.build("simulated", rig, scene, None, 0.0)
        with backend.devices as devices:
            readings = align.Readings(rig.axes)
            for fine in (False, True):
                found = align.fly_cross(
                    devices, rig, center, "detector_elevation", settings, readings, 0, fine
                )[1]
                center = center.copy()
                center[rig.axes.index("detector_elevation")] = found
        backend.close()
        j = rig.axes.index("detector_elevation")
        both = [
            align.peak_at(np.array(r)[:, j], np.array(v))
            for r, v in _ways(readings, rig.axes, "detector_elevation")
        ]
        peaks[latency] = (found, both)
    velocity = align.fly_sweep(rig, settings, "detector_elevation", True).velocity
    shift = np.degrees(np.subtract(*peaks[2e-3][1]) - np.subtract(*peaks[0.0][1]))
    assert abs(shift) == pytest.approx(np.degrees(2 * velocity * 2e-3), rel=0.3)
    assert np.degrees(abs(peaks[2e-3][0] - peaks[0.0][0])) <= 0.001


def _ways(
    readings: align.Readings, axes: tuple[str, ...], joint: str
) -> list[tuple[list[list[float]], list[float]]]:
    """The last two sweeps' (read-back, values) of ``joint``: the fine scan's two ways,
    told apart by the pose each was sent to."""
    rows = [i for i, name in enumerate(readings.joint) if name == joint]
    targets = [tuple(readings.commanded[i]) for i in rows]
    ways = list(dict.fromkeys(targets))[-2:]
    return [
        (
            [readings.read_back[i] for i, t in zip(rows, targets, strict=True) if t == way],
            [readings.value[i] for i, t in zip(rows, targets, strict=True) if t == way],
        )
        for way in ways
    ]


def test_a_detector_that_cannot_stream_scans_stop_and_go(tmp_path: Path) -> None:
    """A lock-in (each reading waits its output filter): the check's short scan, stop
    and go, recovering its peaks as a fly scan does."""
    rig = Rig.from_yaml(ARCH)
    data = yaml.safe_load(mirror_scene(tmp_path, TRUTH).read_text())
    lockin = yaml.safe_load((CONFIGS / "scenes" / "matte_lockin.yaml").read_text())["detector"]
    data["detector"] = {**lockin, "sensitivity_v": 1.0}
    data["effects"] = {"misalignment": data["effects"]["misalignment"]}
    (tmp_path / "lockin.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
    scene = load_scene(tmp_path / "lockin.yaml", rig)
    settings = align.ScanSettings(
        incidences_deg=(30.0, 55.0), azimuths_deg=(60.0,), rotations_deg=(0.0,), exposure_s=0.1
    )  # two incidences the rig reaches: scanned as given (`align.for_rig`)
    result = align.run_scan(rig, scene, "simulated", settings)
    assert result.mode == align.STOP_AND_GO
    assert set(result.readings.mode) == {"stop_and_go"} and len(result.peaks) == 2
    photodiode = load_scene(mirror_scene(tmp_path, TRUTH), rig)
    streaming = align.run_scan(rig, photodiode, "simulated", replace(settings, exposure_s=1e-3))
    assert streaming.mode == align.FLY
    assert np.degrees(np.abs(result.peaks - streaming.peaks)).max() <= 0.003


@pytest.mark.pty
@pytest.mark.xdist_group("pty")
def test_on_the_rehearsal_path_at_real_speed_the_scan_flies_to_the_stop_and_go_peaks(
    tmp_path: Path,
) -> None:
    """The emulated Dynamixel arm polled over its pty and the serial photometer
    streaming, at real speed: each peak's fly scans (the fine one at the hardware's 25
    Hz, both ways) land where the stop-and-go rehearsal (0.0003° from the truth) puts
    it; faster than real time the rehearsal scans stop-and-go."""
    text = (CONFIGS / "rigs" / "arch_serial.yaml").read_text(encoding="utf-8")
    (tmp_path / "arch_serial.yaml").write_text(text.replace("../", f"{CONFIGS}/"), "utf-8")
    rig = Rig.from_yaml(tmp_path / "arch_serial.yaml")
    scene = load_scene(mirror_scene(tmp_path, TRUTH), rig)
    settings = align.ScanSettings(incidences_deg=(45.0, 65.0), azimuths_deg=(0.0,),
                                  rotations_deg=(0.0,))  # fmt: skip
    flown = align.run_scan(rig, scene, "rehearsal", settings, speedup=1.0)
    still = align.run_scan(rig, scene, "rehearsal", settings, speedup=1e6)
    assert flown.mode == align.FLY and set(flown.readings.mode) == {"fly"}
    assert still.mode == align.STOP_AND_GO and len(flown.peaks) == len(still.peaks) == 2
    el, az = rig.axes.index("detector_elevation"), rig.axes.index("detector_azimuth")
    miss = np.degrees(flown.peaks - still.peaks)
    arc = np.abs(np.sin(still.peaks[:, el]))  # an azimuth turn moves the detector sin θo
    assert np.all(np.abs(miss[:, el]) <= 0.01), miss
    assert np.all(np.abs(miss[:, az]) * arc <= 0.01), miss
    # On the run's clock: the fine sweeps' readings 1/25 s apart, each the exposure long.
    readings = flown.readings
    started, ended = np.array(readings.started_s), np.array(readings.ended_s)
    assert np.allclose(ended - started, settings.exposure_s, atol=1e-9)
    steps = np.diff(ended)
    fine = steps[np.abs(steps - 1.0 / align.HARDWARE_FINE_RATE_HZ) < 1e-3]
    assert len(fine) >= 2 * 2 * 2 * 14  # peaks, joints, ways: 15 points (14 steps) or more
