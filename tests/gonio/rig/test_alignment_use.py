"""The alignment a rig file names (``alignment:``): loaded with the rig, its mistakes one
line naming the file and the field, stored by the plans and runs made with it, and
shown by `gonio info`."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from gonio.config import ConfigError
from gonio.planner import content_hash
from gonio.rig import AlignmentSpec, Rig
from gonio.rig.alignment_file import AlignmentFile, text
from gonio.rig.sensitivity import alignment_sigma
from gonio.store import open_run
from tests.conftest import CONFIGS, CliResult
from tests.support.alignment import fit_record

Gonio = Callable[..., CliResult]

SPEC = AlignmentSpec(
    zero_offset_deg={"light_elevation": 0.3, "detector_elevation": -0.2},
    tilt_deg=0.4,
    tilt_azimuth_deg=30.0,
    detector_pointing_deg=(0.1, 0.0),
)


def aligned_rig(tmp_path: Path, spec: AlignmentSpec = SPEC, rig: str = "arch") -> Path:
    """A copy of a shipped rig file naming an alignment file beside it."""
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=spec)))
    path = tmp_path / f"{rig}.yaml"
    path.write_text((CONFIGS / "rigs" / f"{rig}.yaml").read_text() + "alignment: align.yaml\n")
    return path


def test_a_rig_without_alignment_has_none(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    assert rig.alignment.is_none and rig.alignment_file is None and rig.alignment_text is None


def test_the_rig_holds_the_alignment_its_file_names(tmp_path: Path) -> None:
    rig = Rig.from_yaml(aligned_rig(tmp_path))
    expected = SPEC.alignment(rig.axes)
    assert np.array_equal(rig.alignment.zero_offset, expected.zero_offset)
    assert float(rig.alignment.tilt) == float(expected.tilt)
    assert rig.alignment_text == (tmp_path / "align.yaml").read_bytes()
    # The stored bytes stand in for the file (a run or a plan rebuilds the rig from them).
    (tmp_path / "align.yaml").unlink()
    again = Rig.from_yaml(tmp_path / "arch.yaml", alignment_raw=rig.alignment_text)
    assert np.array_equal(again.alignment.zero_offset, rig.alignment.zero_offset)


def test_a_missing_alignment_file_is_one_line_naming_the_rig_file(tmp_path: Path) -> None:
    path = aligned_rig(tmp_path)
    (tmp_path / "align.yaml").unlink()
    with pytest.raises(ConfigError) as exc:
        Rig.from_yaml(path)
    message = str(exc.value)
    assert "\n" not in message and message.startswith(f"{path}: alignment: cannot read")


def test_a_bad_alignment_file_is_one_line_naming_its_field(tmp_path: Path) -> None:
    path = aligned_rig(tmp_path)
    (tmp_path / "align.yaml").write_text("alignment:\n  tilt_deg: 40\n")
    with pytest.raises(ConfigError) as exc:
        Rig.from_yaml(path)
    assert "align.yaml:2: alignment.tilt_deg:" in str(exc.value)


def test_an_offset_of_another_rigs_axis_is_one_line(tmp_path: Path) -> None:
    path = aligned_rig(tmp_path, AlignmentSpec(zero_offset_deg={"light_arm": 0.1}))
    with pytest.raises(ConfigError) as exc:
        Rig.from_yaml(path)
    message = str(exc.value)
    assert "\n" not in message
    assert "align.yaml: alignment.zero_offset_deg.light_arm: no such axis" in message


def test_the_cli_refuses_a_bad_reference_with_exit_2(run_gonio: Gonio, tmp_path: Path) -> None:
    rig = aligned_rig(tmp_path)
    (tmp_path / "align.yaml").unlink()
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        (CONFIGS / "plans" / "quick.yaml")
        .read_text()
        .replace("rig: ../rigs/arch.yaml", f"rig: {rig}")
    )
    r = run_gonio("plan", str(plan), "-o", str(tmp_path / "plan.csv"))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "alignment: cannot read the alignment file" in r.stderr


def test_a_run_stores_the_alignment_and_info_shows_it(run_gonio: Gonio, tmp_path: Path) -> None:
    rig = aligned_rig(tmp_path)
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        (CONFIGS / "plans" / "quick.yaml")
        .read_text()
        .replace("rig: ../rigs/arch.yaml", f"rig: {rig}")
        .replace("target: 500", "target: 40")
    )
    out = tmp_path / "run.sqlite"
    r = run_gonio(
        "simulate", str(plan), "--scene", str(CONFIGS / "scenes" / "matte.yaml"), "-o", str(out)
    )
    assert r.returncode == 0, r.stderr
    run = open_run(out)
    stored = (tmp_path / "align.yaml").read_text()
    assert run.meta["alignment_text"] == stored
    assert run.meta["alignment_path"] == str((tmp_path / "align.yaml").resolve())
    expected = SPEC.alignment(run.plan.rig.axes).zero_offset
    assert np.array_equal(run.plan.rig.alignment.zero_offset, expected)
    # The recorded pairs are those of the true geometry at the read-back angles.
    rig_ = run.plan.rig
    q = np.stack([run.samples[f"{a}_read_back_rad"] for a in rig_.axes], axis=1)
    wi, wo = rig_.forward(q, rig_.alignment)
    assert np.array_equal(run.directions()[0], wi) and np.array_equal(run.directions()[1], wo)
    assert not np.allclose(rig_.forward(q)[0], wi)
    info = run_gonio("info", str(out))
    assert info.returncode == 0
    assert "alignment" in info.stdout and "align.yaml" in info.stdout
    assert "set by hand" in info.stdout
    # Re-derived with another alignment file: the export's pairs follow it.
    later = tmp_path / "later.yaml"
    later.write_text(text(AlignmentFile(alignment=AlignmentSpec(tilt_deg=1.0))))
    csv = tmp_path / "run.csv"
    r = run_gonio("export", str(out), "--format", "csv", "-o", str(csv), "--alignment", str(later))
    assert r.returncode == 0, r.stderr
    plain = tmp_path / "plain.csv"
    assert run_gonio("export", str(out), "--format", "csv", "-o", str(plain)).returncode == 0
    assert csv.read_text() != plain.read_text()
    for command in (
        ("evaluate", str(out)),
        ("export", str(out), "--format", "csv", "-o", str(tmp_path / "x.csv")),
    ):
        bad = run_gonio(*command, "--alignment", str(tmp_path / "nowhere.yaml"))
        assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
        assert "nowhere.yaml" in bad.stderr


def test_the_alignment_is_part_of_what_a_run_is_made_from(run_gonio: Gonio, tmp_path: Path) -> None:
    """The run's content hash covers the alignment file's bytes (with the plan's stored
    copy), and a resume refuses an alignment file changed since the run started unless
    forced, naming the file."""
    rig = aligned_rig(tmp_path)
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        (CONFIGS / "plans" / "quick.yaml")
        .read_text()
        .replace("rig: ../rigs/arch.yaml", f"rig: {rig}")
        .replace("target: 500", "target: 30")
    )
    out = tmp_path / "run.sqlite"
    scene = str(CONFIGS / "scenes" / "matte.yaml")
    r = run_gonio("acquire", str(plan), "--scene", scene, "-o", str(out))
    assert r.returncode == 0, r.stderr
    run = open_run(out)
    hashes = run.meta["hashes"]
    texts = [(tmp_path / n).read_bytes() for n in ("plan.yaml", "arch.yaml")]
    align = (tmp_path / "align.yaml").read_bytes()
    assert hashes["content"] == content_hash(*texts, Path(scene).read_bytes(), align)
    assert hashes["alignment_sha256"] == hashlib.sha256(align).hexdigest()
    assert hashes["content"] != content_hash(*texts, Path(scene).read_bytes())
    assert run.plan.content_hash(Path(scene).read_bytes()) == hashes["content"]
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=AlignmentSpec())))
    refused = run_gonio("acquire", "--resume", str(out))
    assert refused.returncode == 2, refused.stderr
    assert refused.stderr.strip() == (
        f"gonio: error: {(tmp_path / 'align.yaml').resolve()}: the alignment file changed "
        "since the run started (sha256 differs from the journal's); restore it, or resume "
        "with --force to accept the change"
    )
    (tmp_path / "align.yaml").write_bytes(align)
    assert run_gonio("acquire", "--resume", str(out)).returncode == 0


def test_info_says_none_without_an_alignment(run_gonio: Gonio, tmp_path: Path) -> None:
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        (CONFIGS / "plans" / "quick.yaml")
        .read_text()
        .replace("rig: ../rigs/arch.yaml", f"rig: {CONFIGS / 'rigs' / 'arch.yaml'}")
        .replace("target: 500", "target: 40")
    )
    out = tmp_path / "run.sqlite"
    r = run_gonio(
        "simulate", str(plan), "--scene", str(CONFIGS / "scenes" / "matte.yaml"), "-o", str(out)
    )
    assert r.returncode == 0, r.stderr
    assert "none" in run_gonio("info", str(out)).stdout.split("alignment")[-1].split("\n")[0]
    assert "alignment_text" not in open_run(out).meta


def test_the_alignments_standard_errors_reach_the_directions(tmp_path: Path) -> None:
    record = fit_record({"zero_offset.light_elevation": (0.3, 0.05)})
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=SPEC, fit=record)))
    path = tmp_path / "arch.yaml"
    path.write_text((CONFIGS / "rigs" / "arch.yaml").read_text() + "alignment: align.yaml\n")
    rig = Rig.from_yaml(path)
    wi = np.array([[0.3, 0.1, 0.9], [-0.5, 0.2, 0.7]])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo = wi * np.array([-1.0, -1.0, 1.0])
    q = rig.solve(wi, wo).angles
    # Only the light's elevation is uncertain: it moves ωi by its error, ωo not at all;
    # the RMS over the pair's two directions is σ/√2.
    np.testing.assert_allclose(alignment_sigma(rig, q), np.radians(0.05) / np.sqrt(2), rtol=1e-6)
    assert np.all(alignment_sigma(Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml"), q) == 0.0)


@pytest.mark.parametrize(
    ("rho", "factor"), [(0.0, math.sqrt(2.0)), (1.0, 2.0), (-1.0, 0.0), (None, math.sqrt(2.0))]
)
def test_the_stated_correlations_reach_the_directions(
    tmp_path: Path, rho: float | None, factor: float
) -> None:
    """The light's elevation zero and its pointing about the same axis turn ωi alike:
    with equal errors σ the light direction's error is σ√(2 + 2ρ) (independent without
    a stated correlation), so the pair's RMS is that over √2."""
    error = 0.05
    record = fit_record(
        {"zero_offset.light_elevation": (0.3, error), "light_pointing_y": (0.0, error)},
        None if rho is None else [[1.0, rho], [rho, 1.0]],
    )
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=SPEC, fit=record)))
    path = tmp_path / "arch.yaml"
    path.write_text((CONFIGS / "rigs" / "arch.yaml").read_text() + "alignment: align.yaml\n")
    rig = Rig.from_yaml(path)
    wi = np.array([[0.3, 0.1, 0.9], [-0.5, 0.2, 0.7]])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    q = rig.solve(wi, wi * np.array([-1.0, -1.0, 1.0])).angles
    expected = np.radians(error) * factor / np.sqrt(2.0)
    np.testing.assert_allclose(alignment_sigma(rig, q), expected, rtol=1e-6, atol=1e-10)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("[[1.0]]", "expected 2 rows of 2"),
        ("[[1.0, 0.5], [0.4, 1.0]]", "expected a symmetric matrix"),
        ("[[0.9, 0.5], [0.5, 1.0]]", "expected 1 on the diagonal"),
        ("[[1.0, 1.5], [1.5, 1.0]]", "less than or equal to 1"),
    ],
)
def test_a_bad_correlation_matrix_is_one_line(tmp_path: Path, rows: str, message: str) -> None:
    record = fit_record(
        {"zero_offset.light_elevation": (0.3, 0.05), "light_pointing_y": (0.0, 0.05)}
    )
    body = text(AlignmentFile(alignment=SPEC, fit=record))
    assert "  correlation: null\n" in body
    body = body.replace("  correlation: null", f"  correlation: {rows}")
    (tmp_path / "align.yaml").write_text(body)
    path = tmp_path / "arch.yaml"
    path.write_text((CONFIGS / "rigs" / "arch.yaml").read_text() + "alignment: align.yaml\n")
    with pytest.raises(ConfigError, match=message) as caught:
        Rig.from_yaml(path)
    assert all("align.yaml" in line for line in str(caught.value).splitlines())


def test_a_correlation_matrix_no_covariance_has_is_refused() -> None:
    with pytest.raises(ValidationError, match="expected a positive semi-definite matrix"):
        fit_record(
            dict.fromkeys(("tilt_x", "tilt_y", "height_mm"), (0.0, 0.05)),
            [[1.0, 0.9, -0.9], [0.9, 1.0, 0.9], [-0.9, 0.9, 1.0]],
        )
