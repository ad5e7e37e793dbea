"""Scene files: the shipped scenes load; each mistake is one line naming the file, the
line, the field and what was expected."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.config import ConfigError
from sim.scene import EffectsSpec, Scene, load_scene

SCENES = Path(__file__).resolve().parents[2] / "configs" / "scenes"
SHIPPED = sorted(p.stem for p in SCENES.glob("*.yaml"))
MATTE = yaml.safe_load((SCENES / "matte.yaml").read_text())


def test_shipped_scenes_load() -> None:
    assert {"matte", "glossy_metal", "brushed_metal", "seed000_specular"} <= set(SHIPPED)
    scenes = {name: load_scene(SCENES / f"{name}.yaml") for name in SHIPPED}
    assert scenes["matte"].effects.names() == (
        "shot_noise", "read_noise", "dark_current", "quantization", "saturation",
    )  # fmt: skip
    assert scenes["glossy_metal"].material.model().is_rgb
    assert not scenes["brushed_metal"].material.model().isotropic
    assert scenes["seed000_specular"].effects.names() == ()
    assert scenes["seed000_specular"].source.kind == "point"
    assert scenes["brushed_metal"].effects.position_error is not None
    assert scenes["brushed_metal"].effects.position_error.backlash_deg == 0.1


@pytest.mark.parametrize(
    "form",
    [["shot_noise", "footprint"], {"shot_noise": None, "footprint": {}}],
    ids=["list", "mapping"],
)
def test_effects_as_a_list_or_a_mapping(form: Any) -> None:
    spec = EffectsSpec.model_validate(form)
    assert spec.names() == ("shot_noise", "footprint")


def test_with_effects_replaces_them() -> None:
    scene = Scene.model_validate(MATTE)
    assert scene.with_effects([]).effects.names() == ()
    drift = scene.with_effects({"source_drift": {"rate_per_hour": 0.1}})
    assert drift.effects.names() == ("source_drift",)
    assert drift.effects.source_drift is not None
    assert drift.effects.source_drift.rate_per_hour == 0.1


def write(tmp_path: Path, data: dict[str, Any]) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


CASES = [
    ("unknown-model", {"material": {"name": "velvet"}}, "material.name", "unknown BRDF model"),
    (
        "bad-parameter",
        {"material": {"name": "cook_torrance", "alpha": -1}},
        "material.name",
        "parameter alpha must lie in",
    ),
    ("unknown-effect", {"effects": ["shot_noise", "lens_flare"]}, "effects.lens_flare", "Extra"),
    (
        "bad-effect-parameter",
        {"effects": {"source_drift": {"amplitude": 2}}},
        "effects.source_drift.amplitude",
        "less than 1",
    ),
    (
        "unknown-source-kind",
        {"source": {"kind": "laser", "irradiance_w_m2": 1, "beam_diameter_mm": 2}},
        "source",
        "'collimated', 'point'",
    ),
    (
        "negative-aperture",
        {"detector": {**MATTE["detector"], "aperture_sr": -1}},
        "detector.aperture_sr",
        "greater than 0",
    ),
    (
        "exposure-range-inverted",
        {"detector": {**MATTE["detector"], "exposure_range_s": [1, 0.1]}},
        "detector.exposure_range_s",
        "expected [min, max] with 0 < min ≤ max",
    ),
    (
        "albedo-above-one",
        {"reference": {"albedo": 1.2}},
        "reference.albedo",
        "less than or equal to 1",
    ),
]


@pytest.mark.parametrize(
    ("change", "field", "words"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_bad_scene_is_one_line(
    tmp_path: Path, change: dict[str, Any], field: str, words: str
) -> None:
    path = write(tmp_path, {**MATTE, **change})
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:"), message
    assert f": {field}: " in message, message
    assert words in message


def test_missing_scene_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read the file"):
        load_scene(tmp_path / "none.yaml")


@pytest.mark.parametrize("name", SHIPPED)
def test_a_dump_reads_back_as_the_same_scene(name: str) -> None:
    scene = load_scene(SCENES / f"{name}.yaml")
    assert Scene.model_validate(scene.model_dump()) == scene
    assert Scene.model_validate(scene.with_effects([]).model_dump()).effects.names() == ()
