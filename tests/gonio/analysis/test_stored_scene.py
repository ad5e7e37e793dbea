"""A simulated run's stored scene, read by analysis through the scene file's own schema
(`gonio.scene`): for every shipped scene the band, the effects and the misalignment are
what the simulator's `Scene` reads; each section is validated only when read (a band
needs nothing of the material); an edited section is one line naming the field."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.analysis.scene import scene_alignment, scene_band, scene_effects, scene_truth
from gonio.config import ConfigError
from gonio.rig import Rig
from gonio.scene import Scene, load_scene
from tests.conftest import CONFIGS

SCENES = sorted((CONFIGS / "scenes").glob("*.yaml"))
MATTE = yaml.safe_load((CONFIGS / "scenes" / "matte.yaml").read_text())


def _text(**changes: object) -> str:
    return yaml.safe_dump({**MATTE, **changes})


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_each_shipped_scene_reads_as_the_simulator_reads_it(path: Path) -> None:
    scene, text = load_scene(path), path.read_text()
    assert scene_band(text) == scene.detector.band
    assert scene_effects(text) == frozenset(scene.effects.names())
    assert scene_alignment(text, ("a", "b")) is None


def test_bands_and_effects_as_the_scene_declares_them() -> None:
    detector = {**MATTE["detector"], "band": "g"}
    text = _text(detector=detector, effects=["shot_noise", "footprint"])
    scene = Scene.model_validate(yaml.safe_load(text))
    assert scene_band(text) == "g" == scene.detector.band
    assert scene_effects(text) == {"shot_noise", "footprint"} == set(scene.effects.names())
    mapping = _text(effects={"source_drift": None, "stray_light": {"power_w": 1e-9}})
    assert scene_effects(mapping) == {"source_drift", "stray_light"}
    assert scene_band(_text(detector={k: v for k, v in detector.items() if k != "band"})) == (
        "luminance"
    )


def test_the_misalignment_is_the_scenes(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    effects = {"misalignment": {"zero_offset_deg": {rig.axes[0]: 0.3}, "tilt_deg": 0.2}}
    text = _text(effects=effects)
    spec = Scene.model_validate(yaml.safe_load(text)).effects.misalignment
    assert spec is not None
    got, want = scene_alignment(text, rig.axes), spec.alignment(rig.axes)
    assert got is not None
    np.testing.assert_array_equal(got.zero_offset, want.zero_offset)
    assert got.zero_offset[0] == np.radians(0.3) and float(got.tilt) == np.radians(0.2)
    with pytest.raises(ConfigError, match=r"^scene \(as stored in the run\): effects\.misal"):
        scene_alignment(text, ("x", "y"))


def test_the_band_needs_nothing_of_the_material() -> None:
    text = _text(material={"name": "merl", "path": "gone.binary"}, detector={"band": "r"})
    assert scene_band(text) == "r"
    with pytest.raises(ConfigError, match=r"^run\.yaml \(as stored in the run\): material\."):
        scene_truth(text, "run.yaml")


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"detector": {"band": "ultraviolet"}}, "detector.band: Input should be 'luminance'"),
        ({"effects": ["shot_noise", "sparkle"]}, "effects.sparkle: Extra inputs are not permitted"),
        ({"effects": {"source_drift": {"rate_per_hour": 9}}}, "effects.source_drift.rate_per"),
        ({"effects": 3}, "effects: "),
    ],
)
def test_an_edited_section_is_one_line(changes: dict[str, object], words: str) -> None:
    text = _text(**changes)
    reads = (scene_band,) if "detector" in changes else (scene_effects,)
    for read in reads:
        with pytest.raises(ConfigError) as info:
            read(text)
        message = str(info.value)
        assert message.startswith("scene (as stored in the run): ") and "\n" not in message
        assert words in message, message
