"""`SceneOptics(scene, rig)`: the instrument's constants come from the rig, what the
simulation adds from the scene."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from gonio import radiometry
from gonio.rig.model import Rig
from gonio.scene import Scene, load_scene
from sim.virtual.physics.optics import SceneOptics
from tests.support.rigs import direction, rig_with

SCENES = Path(__file__).resolve().parents[4] / "configs" / "scenes"
MATTE = load_scene(SCENES / "matte.yaml")


def test_the_source_is_the_rigs_light_with_the_scenes_power(
    arch_point: Rig, rigs: dict[str, Rig]
) -> None:
    optics = SceneOptics(MATTE, rigs["arch"])
    assert optics.source == radiometry.CollimatedSource(1.0, 6.0)
    assert optics.optics == radiometry.DetectorOptics(1e-5, 25.0)
    assert optics.diameters_mm == {"sample": 30.0, "reference": 50.8}
    point = SceneOptics(load_scene(SCENES / "seed000_specular.yaml"), arch_point)
    assert point.source == radiometry.PointSource(0.002, 300.0)


def test_sizes_aperture_and_reference_follow_the_rig(rigs: dict[str, Rig]) -> None:
    rig = rig_with(
        rigs["arch"],
        detector={"aperture_sr": 2e-4},
        constraints={"beam_diameter_mm": 4, "detector_fov_mm": 20, "sample_diameter_mm": 50},
        reference={"albedo": 0.5, "diameter_mm": None},
    )
    optics = SceneOptics(MATTE, rig)
    assert optics.source == radiometry.CollimatedSource(1.0, 4.0)
    assert optics.optics == radiometry.DetectorOptics(2e-4, 20.0)
    assert optics.diameters_mm == {"sample": 50.0, "reference": 50.0}  # in the sample holder
    sized = SceneOptics(MATTE, rig_with(rig, reference={"diameter_mm": 60}))
    assert sized.diameters_mm == {"sample": 50.0, "reference": 60.0}
    wi, wo = direction(0.0, 0.0)[None], direction(45.0, 180.0)[None]
    np.testing.assert_allclose(optics.models["reference"](wi, wo), 0.5 / math.pi, rtol=1e-15)
    # The power scales with the aperture the rig gives (no effects: Φ = f · G).
    base = SceneOptics(MATTE.with_effects([]), rigs["arch"]).geometric_power(wi, wo)
    wider = SceneOptics(
        MATTE.with_effects([]), rig_with(rigs["arch"], detector={"aperture_sr": 2e-4})
    ).geometric_power(wi, wo)
    np.testing.assert_allclose(wider / base, 20.0, rtol=1e-12)


def test_the_band_and_responsivity_are_the_scenes(rigs: dict[str, Rig]) -> None:
    data = MATTE.model_dump()
    data["detector"] = {**data["detector"], "responsivity_a_w": 0.25}
    half = SceneOptics(Scene.model_validate(data), rigs["arch"])
    full = SceneOptics(MATTE, rigs["arch"])
    power, exposure = np.array([1e-9]), np.array([0.1])
    np.testing.assert_allclose(
        half.electrons(power[:, None], exposure), 0.5 * full.electrons(power[:, None], exposure)
    )
