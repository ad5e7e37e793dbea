"""A mirror scan on the simulated rig, misaligned by the scene, fitted back
(`gonio.rig.alignment_fit`): cross scans of the detector through each nominal specular
pose locate the peaks the true geometry puts elsewhere, and the fit recovers every
parameter the scan determines within 0.03° (the combinations that act alike as one)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from gonio.config import ConfigError
from gonio.errors import GonioError
from gonio.rig.alignment_file import from_fit, load_alignment, text
from gonio.rig.alignment_fit import AlignmentFit, fit, peak_at, peak_offsets, stated_covariance
from gonio.rig.model import Rig
from gonio.scene import load_scene
from sim.virtual.simulate import simulate
from tests.conftest import CONFIGS
from tests.sim.virtual.test_misalignment import Sweep, misaligned

TRUTH = {
    "zero_offset_deg": {
        "light_elevation": 0.7, "detector_azimuth": -0.4, "detector_elevation": 0.5,
        "sample_rotation": 0.3,
    },
    "tilt_deg": 0.5, "tilt_azimuth_deg": 40.0,
    "light_pointing_deg": (0.3, -0.2), "detector_pointing_deg": (-0.25, 0.3),
}  # fmt: skip
ARCH = CONFIGS / "rigs" / "arch.yaml"
#: Coarse then fine offsets (°) of the cross scans.
SCANS = (
    np.arange(-4.0, 4.0001, 0.1),
    np.arange(-0.3, 0.3001, 0.005),
    np.arange(-0.3, 0.3001, 0.005),
)


def nominal_poses(rig: Rig) -> np.ndarray:
    """The rig file's specular poses of a mirror: 4 incidences × 4 azimuths, at three
    stage rotations."""
    theta = np.radians([20.0, 35.0, 50.0, 65.0])[:, None]
    phi = np.radians([0.0, 90.0, 180.0, 270.0])[None, :]
    wi = np.stack(np.broadcast_arrays(
        np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)
    ), axis=-1).reshape(-1, 3)  # fmt: skip
    poses = []
    for rotation in np.radians([0.0, 120.0, 240.0]):
        c, s = math.cos(rotation), math.sin(rotation)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        solution = rig.solve(wi @ turn.T, (wi * (-1.0, -1.0, 1.0)) @ turn.T)
        poses.append(solution.angles[solution.ok])
    return np.concatenate(poses)


@pytest.fixture(scope="module")
def scanned(tmp_path_factory: pytest.TempPathFactory) -> tuple[Rig, AlignmentFit]:
    """The arch rig and the fit of a simulated mirror scan of it misaligned by `TRUTH`."""
    rig = Rig.from_yaml(ARCH)
    mirror = tmp_path_factory.mktemp("scan") / "mirror.yaml"  # the glossy metal, sharper
    text = (CONFIGS / "scenes" / "glossy_metal.yaml").read_text(encoding="utf-8")
    mirror.write_text(text.replace("alpha: 0.05", "alpha: 0.005"), encoding="utf-8")
    scene = misaligned(load_scene(mirror, rig), [], **TRUTH)
    peaks = nominal_poses(rig)
    for offsets in (np.radians(s) for s in SCANS):
        for joint in (rig.axes.index("detector_elevation"), rig.axes.index("detector_azimuth")):
            poses = np.repeat(peaks[:, None, :], len(offsets), axis=1)
            poses[:, :, joint] += offsets
            values = simulate(Sweep(rig, poses.reshape(-1, len(rig.axes))), scene).value
            peaks[:, joint] += peak_offsets(offsets, values.reshape(len(peaks), -1))
    return rig, fit(rig, peaks, math.radians(0.002))


def test_a_simulated_mirror_scan_recovers_the_misalignment(
    scanned: tuple[Rig, AlignmentFit],
) -> None:
    _, result = scanned
    d = dict(zip(result.names, np.degrees(result.values), strict=True))
    zero = TRUTH["zero_offset_deg"]
    assert d["zero_offset.detector_azimuth"] == pytest.approx(zero["detector_azimuth"], abs=0.03)
    azimuth = math.radians(TRUTH["tilt_azimuth_deg"] + zero["sample_rotation"])  # as read
    assert d["tilt_x"] == pytest.approx(0.5 * math.cos(azimuth), abs=0.03)
    assert d["tilt_y"] == pytest.approx(0.5 * math.sin(azimuth), abs=0.03)
    assert d["light_pointing_x"] == pytest.approx(0.3, abs=0.03)
    light = d["zero_offset.light_elevation"] + d["light_pointing_y"]
    detector = d["zero_offset.detector_elevation"] + d["detector_pointing_y"]
    assert light == pytest.approx(0.7 - 0.2, abs=0.03)
    assert detector == pytest.approx(0.5 + 0.3, abs=0.03)
    assert "height_mm" in result.hints


def test_the_alignment_file_holds_the_fit_and_reads_back(
    scanned: tuple[Rig, AlignmentFit], tmp_path: Path
) -> None:
    rig, result = scanned
    run = tmp_path / "scan.sqlite"
    run.write_bytes(b"the scan")
    made = from_fit(result, rig, ARCH.read_bytes(), run, run.read_bytes(), "2026-12-07T11:30:00Z")
    path = tmp_path / "arch.alignment.yaml"
    path.write_text(text(made), encoding="utf-8")
    assert path.read_text(encoding="utf-8").startswith("# gonio alignment v1\n")
    back = load_alignment(path)
    assert back == made and back.fit is not None
    assert back.fit.parameters["zero_offset.detector_azimuth"].value == pytest.approx(
        -0.4, abs=0.03
    )
    assert "height_mm" in back.fit.undetermined and back.fit.peaks == len(result.residuals_rad)
    # the alignment the file gives moves the rig as the fit found it
    wi, wo = rig.forward(nominal_poses(rig), back.alignment.alignment(rig.axes))
    fitted = rig.forward(nominal_poses(rig), result.alignment)
    np.testing.assert_allclose(wi, fitted[0], atol=1e-12)
    np.testing.assert_allclose(wo, fitted[1], atol=1e-12)
    # the file states the fit's covariance of what it determines (errors, correlations),
    # as the rig that names it reads it back
    kept = np.flatnonzero(result.determined)
    assert back.fit.correlation is not None and len(back.fit.correlation) == len(kept)
    stated = stated_covariance(rig.realigned(path))
    expected = np.zeros_like(result.covariance)
    expected[np.ix_(kept, kept)] = result.covariance[np.ix_(kept, kept)]
    np.testing.assert_allclose(stated, expected, rtol=1e-9, atol=1e-30)
    assert np.any(np.abs(np.array(back.fit.correlation) - np.eye(len(kept))) > 0.01)


def test_a_bad_alignment_file_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("alignment:\n  tilt_deg: 30\n", encoding="utf-8")
    with pytest.raises(
        ConfigError, match=r"bad.yaml:2: alignment.tilt_deg: .*less than or equal to 5"
    ):
        load_alignment(path)


def test_a_scan_that_misses_its_peak_is_one_line() -> None:
    offsets = np.radians(np.arange(-1.0, 1.0001, 0.1))
    with pytest.raises(GonioError, match="on its edge; widen the scan"):
        peak_offsets(offsets, np.exp(-((offsets[None, :] - 0.5) ** 2) / 1e-6))
    center = peak_offsets(offsets, np.exp(-((offsets[None, :] - 0.0123) ** 2) / 1e-4))
    assert center[0] == pytest.approx(0.0123, abs=1e-12)  # a Gaussian's vertex is exact


def test_a_peak_is_found_where_the_motors_stood() -> None:
    """Angles read back on a motor's ticks: uneven, repeated; the vertex of the log
    parabola of a Gaussian peak is its centre whatever the spacing."""
    tick = math.radians(360.0 / 4096.0)
    asked = np.radians(np.linspace(-0.3, 0.3, 15)) + 0.0011
    read = np.round(asked / tick) * tick  # where the motors stood
    centre = 0.00123
    values = np.exp(-((read - centre) ** 2) / (2.0 * math.radians(0.1) ** 2))
    assert peak_at(read, values) == pytest.approx(centre, abs=1e-12)
    with pytest.raises(GonioError, match="fewer than three distinct angles"):
        peak_at(np.zeros(5), np.ones(5))
