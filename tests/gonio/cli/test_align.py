"""`gonio align` on the simulated backend, with a scene whose mirror is misaligned by
known values: the written file recovers every parameter the scan determines within
0.03° (the combinations that act alike as one), its readings are the sidecar whose hash
it stores, the scan's instrument time stays within 10 minutes; `--check` holds for that
file and fails for one 0.3° off; refusals are one line, exit 2, nothing written."""

from __future__ import annotations

import contextlib
import io
import math
import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from gonio.cli import main
from gonio.rig import Rig
from gonio.rig.alignment_file import load_alignment, sha256
from gonio.workflows import align
from tests.conftest import CONFIGS, CliResult

TRUTH = {
    "zero_offset_deg": {
        "light_elevation": 0.7,
        "detector_azimuth": -0.4,
        "detector_elevation": 0.5,
        "sample_rotation": 0.3,
    },
    "tilt_deg": 0.5,
    "tilt_azimuth_deg": 40.0,
    "light_pointing_deg": [0.3, -0.2],
    "detector_pointing_deg": [-0.25, 0.3],
}
ARCH = CONFIGS / "rigs" / "arch.yaml"


def mirror_scene(folder: Path, misalignment: dict[str, object] | None) -> Path:
    """The glossy metal made a mirror (GGX α 0.005), misaligned by ``misalignment``."""
    data = yaml.safe_load((CONFIGS / "scenes" / "glossy_metal.yaml").read_text())
    data["material"]["alpha"] = 0.005
    if misalignment is not None:
        data["effects"]["misalignment"] = misalignment
    path = folder / "mirror.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def aligned(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """(rig, scene, stdout) of ``gonio align`` on a copy of the arch rig."""
    folder = tmp_path_factory.mktemp("align")
    rig = folder / "arch.yaml"
    rig.write_bytes(ARCH.read_bytes())
    scene = mirror_scene(folder, TRUTH)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["align", str(rig), "--scene", str(scene)])
    assert code == 0
    return rig, scene, out.getvalue()


def test_the_alignment_file_recovers_the_scenes_misalignment(
    aligned: tuple[Path, Path, str],
) -> None:
    rig, _, printed = aligned
    file = load_alignment(rig.with_name("arch.alignment.yaml"))
    assert file.fit is not None
    d = {name: p.value for name, p in file.fit.parameters.items()}
    s = file.alignment
    zero = TRUTH["zero_offset_deg"]
    assert isinstance(zero, dict)
    assert d["zero_offset.detector_azimuth"] == pytest.approx(zero["detector_azimuth"], abs=0.03)
    azimuth = math.radians(40.0 + zero["sample_rotation"])  # the tilt's azimuth as read
    assert d["tilt_x"] == pytest.approx(0.5 * math.cos(azimuth), abs=0.03)
    assert d["tilt_y"] == pytest.approx(0.5 * math.sin(azimuth), abs=0.03)
    assert d["light_pointing_x"] == pytest.approx(0.3, abs=0.03)
    light = s.zero_offset_deg["light_elevation"] + s.light_pointing_deg[1]
    detector = s.zero_offset_deg["detector_elevation"] + s.detector_pointing_deg[1]
    assert light == pytest.approx(0.7 - 0.2, abs=0.03)
    assert detector == pytest.approx(0.5 + 0.3, abs=0.03)
    assert "height_mm" in file.fit.undetermined
    # the readings are the sidecar the file names, by its hash
    sidecar = rig.with_name("arch.alignment.scan.sqlite")
    assert file.fit.run == str(sidecar) and file.fit.run_sha256 == sha256(sidecar.read_bytes())
    with contextlib.closing(sqlite3.connect(sidecar)) as db:
        rows = db.execute("SELECT COUNT(*), MAX(ended_s) - MIN(ended_s) FROM reading").fetchone()
    assert rows[0] > 1000
    minutes = float(printed.split("instrument time ")[1].split(" min")[0])
    assert minutes <= 10.0 and rows[1] <= 600.0
    assert "zero_offset.detector_azimuth" in printed and "height_mm" in printed


def test_check_holds_for_the_fitted_file_and_fails_for_a_wrong_one(
    aligned: tuple[Path, Path, str], run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    rig, scene, _ = aligned
    good = rig.with_name("arch.alignment.yaml")
    result = run_gonio("align", str(rig), "--scene", str(scene), "--check", str(good))
    assert result.returncode == 0, result.stdout + result.stderr
    assert "holds" in result.stdout
    data = yaml.safe_load(good.read_text())
    data["alignment"]["zero_offset_deg"]["detector_azimuth"] += 0.3
    wrong = tmp_path / "wrong.alignment.yaml"
    wrong.write_text(yaml.safe_dump(data), encoding="utf-8")
    result = run_gonio("align", str(rig), "--scene", str(scene), "--check", str(wrong))
    assert result.returncode == 1 and "MISS" in result.stdout and "drifted" in result.stdout


def test_the_in_plane_rig_scans_across_by_tilting_the_sample(tmp_path: Path) -> None:
    """Its detector moves in the plane of incidence only: the cross direction is the
    sample's tilt; the fit recovers the wedge and the tilt axis's zero."""
    rig = tmp_path / "in_plane.yaml"
    rig.write_bytes((CONFIGS / "rigs" / "in_plane.yaml").read_bytes())
    truth = {"zero_offset_deg": {"light_arm": 0.3, "sample_tilt": 0.2}, "tilt_deg": 0.4}
    scene = mirror_scene(tmp_path, truth)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["align", str(rig), "--scene", str(scene)]) == 0
    fit = load_alignment(rig.with_name("in_plane.alignment.yaml")).fit
    assert fit is not None
    d = {name: p.value for name, p in fit.parameters.items()}
    assert d["zero_offset.sample_tilt"] == pytest.approx(0.2, abs=0.03)
    assert math.hypot(d["tilt_x"], d["tilt_y"]) == pytest.approx(0.4, abs=0.03)


def test_an_azimuth_scan_is_as_wide_in_arc_as_an_elevation_scan() -> None:
    """A detector-azimuth turn moves the detector by sin θo of it: its scans are 1/sin θo
    wider in the joint (a peak 1.5° of arc off at 20° is 4.4° of azimuth off)."""
    rig = Rig.from_yaml(ARCH)
    for theta in (20.0, 65.0):
        pose = align.nominal_poses(rig, align.ScanSettings(incidences_deg=(theta,)))[0]
        factor = align.arc_factor(rig, pose, "detector_azimuth")
        assert factor == pytest.approx(1.0 / math.sin(math.radians(theta)), rel=1e-6)
        assert align.arc_factor(rig, pose, "detector_elevation") == pytest.approx(1.0)


def test_a_rig_that_reaches_few_incidences_is_scanned_over_those_it_does() -> None:
    """The point-source rig sees the spot only up to θo 33.6°: of the default 20° and
    65° it reaches one, so the scan takes the lowest, middle and highest it reaches."""
    settings = align.ScanSettings()
    assert align.for_rig(Rig.from_yaml(ARCH), settings) == settings
    point = Rig.from_yaml(CONFIGS / "rigs" / "arch_point.yaml")
    assert align.for_rig(point, settings).incidences_deg == (5.0, 20.0, 30.0)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["{folder}/none.yaml", "--scene", "{scene}"], "none.yaml"),
        (["{rig}"], "give --scene"),
        (["{rig}", "--scene", "{scene}", "-o", "{folder}/old.yaml"], "exists; give --overwrite"),
        (["{rig}", "--scene", "{scene}", "--check", "{folder}/none.alignment.yaml"], "none"),
        (["{rig}", "--scene", "{scene}", "--exposure", "0"], "expected a positive"),
    ],
)
def test_refusals_are_one_line_and_write_nothing(
    run_gonio: Callable[..., CliResult], tmp_path: Path, args: list[str], message: str
) -> None:
    rig = tmp_path / "arch.yaml"
    rig.write_bytes(ARCH.read_bytes())
    scene = mirror_scene(tmp_path, None)
    (tmp_path / "old.yaml").write_text("old", encoding="utf-8")
    before = sorted(tmp_path.iterdir())
    given = [a.format(folder=tmp_path, rig=rig, scene=scene) for a in args]
    result = run_gonio("align", *given)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and message in result.stderr
    assert sorted(tmp_path.iterdir()) == before


def test_a_scan_that_determines_nothing_is_one_line(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    """A scene with no misalignment is the identity and fits; a scan with no mirror pose
    the rig reaches refuses in one line, writing nothing."""
    rig = tmp_path / "arch.yaml"
    data = yaml.safe_load(ARCH.read_text())
    data["axes"]["light_elevation"]["max_deg"] = 3  # no incidence a scan could use
    rig.write_text(yaml.safe_dump(data), encoding="utf-8")
    scene = mirror_scene(tmp_path, None)
    before = sorted(tmp_path.iterdir())
    result = run_gonio("align", str(rig), "--scene", str(scene))
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert "within the rig's limits" in result.stderr
    assert sorted(tmp_path.iterdir()) == before


@pytest.mark.pty
@pytest.mark.xdist_group("pty")
def test_on_the_rehearsal_path_the_scan_recovers_it_and_the_check_holds(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    """The emulated Dynamixel arm and serial photometer: the motors stand on their
    ticks, so each peak is located in the angles read back; the same recovery."""
    rig = tmp_path / "arch_serial.yaml"
    text = (CONFIGS / "rigs" / "arch_serial.yaml").read_text(encoding="utf-8")
    rig.write_text(text.replace("../", f"{CONFIGS}/"), encoding="utf-8")
    scene = mirror_scene(tmp_path, TRUTH)
    fast = ("--rehearse", "--speedup", "1000000")
    result = run_gonio("align", str(rig), "--scene", str(scene), *fast)
    assert result.returncode == 0, result.stdout + result.stderr
    file = load_alignment(rig.with_name("arch_serial.alignment.yaml"))
    assert file.fit is not None
    d = {name: p.value for name, p in file.fit.parameters.items()}
    assert d["zero_offset.detector_azimuth"] == pytest.approx(-0.4, abs=0.03)
    azimuth = math.radians(40.0 + 0.3)  # the tilt's azimuth as read
    assert d["tilt_x"] == pytest.approx(0.5 * math.cos(azimuth), abs=0.03)
    assert d["tilt_y"] == pytest.approx(0.5 * math.sin(azimuth), abs=0.03)
    good = rig.with_name("arch_serial.alignment.yaml")
    check = run_gonio("align", str(rig), "--scene", str(scene), *fast, "--check", str(good))
    assert check.returncode == 0, check.stdout + check.stderr
