"""A point source's distance as the sample's measured height changes it: divided out of
the calibrated values, the run measures the truth at the pairs the optics saw within
the noise; left in, the values carry the (r / r')² trend across incidence."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.analysis import calibrate, truth_of
from gonio.analysis.lamp_distance import distance_ratio
from gonio.planner import build, load_plan
from gonio.rig import AlignmentSpec, Rig
from gonio.rig.alignment_file import AlignmentFile, text
from gonio.scene import load_scene
from gonio.store.read import Run
from gonio.workflows.simulate import simulate_plan
from tests.conftest import CONFIGS

HEIGHT_MM = 0.5


def measured(folder: Path, rig_name: str, height_mm: float) -> Run:
    """The matte sample with its surface `HEIGHT_MM` above the rotation centre, measured
    by the rig ``rig_name`` whose alignment file says ``height_mm``."""
    (folder / "align.yaml").write_text(
        text(AlignmentFile(alignment=AlignmentSpec(height_mm=height_mm)))
    )
    path = folder / f"{rig_name}.yaml"
    path.write_text((CONFIGS / "rigs" / f"{rig_name}.yaml").read_text() + "alignment: align.yaml\n")
    rig = Rig.from_yaml(path)
    data = yaml.safe_load((CONFIGS / "scenes" / "matte.yaml").read_text())
    data["effects"] = {**{e: {} for e in data["effects"]}, "misalignment": {"height_mm": HEIGHT_MM}}
    if rig.spec.light.kind == "point":
        data["source"] = {"intensity_w_sr": 0.09}  # 1 W/m² at 300 mm
    scene_path = folder / "scene.yaml"
    scene_path.write_text(yaml.safe_dump(data))
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    spec = spec.model_copy(update={"kicks": 0})
    spec = spec.model_copy(update={"sampling": spec.sampling.model_copy(update={"target": 300})})
    return simulate_plan(build(spec, rig), load_scene(scene_path, rig), seed=5).run


def z_scores(run: Run) -> np.ndarray:
    c = calibrate(run)
    return np.asarray((c.brdf - truth_of(run, at_true_pairs=True)) / c.sigma)


@pytest.mark.parametrize("rig_name", ["arch_point"])
def test_the_lamps_distance_is_divided_out(tmp_path: Path, rig_name: str) -> None:
    known = measured(tmp_path, rig_name, HEIGHT_MM)
    ratio = distance_ratio(known)
    assert ratio is not None and np.ptp(ratio) > 2e-3  # 0.5 mm at 300 mm: tenths of %
    z = z_scores(known)
    assert abs(np.mean(z)) < 0.3 and np.std(z) < 1.3
    unknown_folder = tmp_path / "unknown"
    unknown_folder.mkdir()
    unknown = measured(unknown_folder, rig_name, 0.0)
    assert distance_ratio(unknown) is None
    # the same readings without the correction: the trend is many σ
    assert np.quantile(np.abs(z_scores(unknown)), 0.95) > 3.0


def test_a_collimated_beam_needs_none(tmp_path: Path) -> None:
    assert distance_ratio(measured(tmp_path, "arch", HEIGHT_MM)) is None
