"""A run re-derived with a later alignment (`realigned`, ``--alignment``): a run
acquired with the alignment named by its rig file from the start and a run of the same
poses acquired without one, then re-derived with it, hold the same pairs and the same
calibrated values."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import yaml

from gonio.analysis import Measured, calibrate, realigned
from gonio.planner import build, load_plan
from gonio.rig import AlignmentSpec, Rig
from gonio.rig.alignment_file import AlignmentFile, text
from gonio.scene import load_scene
from gonio.workflows.simulate import simulate_plan
from tests.conftest import CONFIGS

#: The alignment the simulated rig really has and its alignment file says.
SPEC = AlignmentSpec(
    zero_offset_deg={"detector_azimuth": 0.4, "detector_elevation": -0.3},
    tilt_deg=0.5,
    tilt_azimuth_deg=20.0,
    detector_pointing_deg=(0.2, 0.0),
)


def test_a_run_re_derived_with_an_alignment_equals_one_acquired_with_it(tmp_path: Path) -> None:
    (tmp_path / "align.yaml").write_text(text(AlignmentFile(alignment=SPEC)))
    rig_path = tmp_path / "arch.yaml"
    rig_path.write_text((CONFIGS / "rigs" / "arch.yaml").read_text() + "alignment: align.yaml\n")
    aligned = Rig.from_yaml(rig_path)
    nominal = Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")
    scene_data = yaml.safe_load((CONFIGS / "scenes" / "matte.yaml").read_text())
    effects = {name: {} for name in scene_data["effects"]}
    scene_data["effects"] = {**effects, "misalignment": SPEC.model_dump(mode="json")}
    scene_path = tmp_path / "scene.yaml"
    scene_path.write_text(yaml.safe_dump(scene_data))
    scene = load_scene(scene_path, aligned)

    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    spec = spec.model_copy(update={"kicks": 0})
    spec = spec.model_copy(update={"sampling": spec.sampling.model_copy(update={"target": 40})})
    plan = build(spec, aligned)
    # The same poses commanded by a rig file without the alignment (so the reference
    # standard too is read at the same pose: the rig solves it in its own geometry).
    plain = dataclasses.replace(plan, rig=nominal)
    with_it = simulate_plan(plan, scene, seed=7).run
    without = simulate_plan(plain, scene, seed=7).run
    assert np.array_equal(with_it.angles(), without.angles())

    again = realigned(without, tmp_path / "align.yaml")
    for a, b in zip(with_it.directions(), again.directions(), strict=True):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12)
    assert not np.allclose(without.directions()[0], with_it.directions()[0], atol=1e-6)
    assert np.array_equal(again.samples["counts"], with_it.samples["counts"])
    # The reference standard was read at the pose each rig solved its calibration
    # geometry with (the aligned rig's reaches it in the true geometry; the plain one's
    # 0.5° off it), at its own times: the two runs' calibrations, not their samples,
    # differ, by the noise of a reading of a Lambertian standard (~1e-7 here).
    np.testing.assert_allclose(calibrate(again).brdf, calibrate(with_it).brdf, rtol=1e-6)
    # Re-deriving a run with the alignment it was acquired with changes nothing.
    same = realigned(with_it, tmp_path / "align.yaml")
    np.testing.assert_allclose(calibrate(same).brdf, calibrate(with_it).brdf, rtol=1e-12)
    m_with = Measured.from_run(with_it)
    m_again = Measured.from_run(without, alignment=tmp_path / "align.yaml")
    np.testing.assert_allclose(m_again.wi, m_with.wi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m_again.f, m_with.f, rtol=1e-6)
    assert again.meta["alignment_text"] == with_it.meta["alignment_text"]
