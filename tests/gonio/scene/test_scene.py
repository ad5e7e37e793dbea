"""Scene files (`gonio.scene`): the shipped scenes load; each mistake is one line
naming the file, the line, the field and what was expected; a fact of the instrument
given in a scene is refused with where it belongs in the rig file; a source power of
the other kind than the rig's light is refused."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from gonio.config import ConfigError
from gonio.planner import build
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig
from gonio.scene import RIG_FIELDS, EffectsSpec, Scene, load_scene
from sim.virtual.physics.optics import SceneOptics
from sim.virtual.simulate import simulate
from tests.conftest import CONFIGS

SCENES = CONFIGS / "scenes"
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
    assert scenes["seed000_specular"].effects.names() == ("saturation",)
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
        "material.alpha",
        "parameter alpha must lie in",
    ),
    (
        "unknown-effect",
        {"effects": ["shot_noise", "lens_flare"]},
        "effects.lens_flare",
        "unknown field",
    ),
    (
        "bad-effect-parameter",
        {"effects": {"source_drift": {"amplitude": 2}}},
        "effects.source_drift.amplitude",
        "less than 1",
    ),
    (
        "no-source-power",
        {"source": {}},
        "source",
        "expected one power: irradiance_w_m2 (a collimated light) or intensity_w_sr",
    ),
    (
        "two-source-powers",
        {"source": {"irradiance_w_m2": 1, "intensity_w_sr": 0.01}},
        "source",
        "expected one power",
    ),
    (
        "negative-power",
        {"source": {"intensity_w_sr": -1}},
        "source.intensity_w_sr",
        "greater than 0",
    ),
    (
        "negative-responsivity",
        {"detector": {**MATTE["detector"], "responsivity_a_w": -1}},
        "detector.responsivity_a_w",
        "greater than 0",
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


#: A value for each fact of the instrument a scene might repeat.
RIG_VALUES: dict[tuple[str, ...], Any] = {
    ("source", "kind"): "collimated",
    ("source", "beam_diameter_mm"): 6,
    ("source", "distance_mm"): 300,
    ("detector", "aperture_sr"): 1e-5,
    ("detector", "fov_diameter_mm"): 25,
    ("detector", "exposure_range_s"): [1e-4, 60],
    ("detector", "readout_s"): 0.0,
    ("detector", "max_averages"): 8,
    ("detector", "interface"): "simulated",
    ("sample",): {"diameter_mm": 30},
    ("reference",): {"albedo": 0.99},
}


def test_every_rig_fact_has_a_case() -> None:
    assert set(RIG_VALUES) == set(RIG_FIELDS)


def line_of_key(path: Path, key: str) -> int:
    """1-based line where the value of ``key`` starts: the key's, or the next one for a
    block mapping or sequence (where `gonio.config` points)."""
    lines = path.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.lstrip().startswith(f"{key}:"))
    return at + 1 + lines[at].rstrip().endswith(":")


@pytest.mark.parametrize("where", list(RIG_VALUES), ids=".".join)
def test_a_fact_of_the_rig_in_a_scene_is_one_line(tmp_path: Path, where: tuple[str, ...]) -> None:
    data = {**MATTE, "detector": dict(MATTE["detector"]), "source": dict(MATTE["source"])}
    if len(where) == 1:
        data[where[0]] = RIG_VALUES[where]
    else:
        data[where[0]][where[1]] = RIG_VALUES[where]
    path = write(tmp_path, data)
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    message = str(info.value)
    field = ".".join(where)
    assert message == (
        f"{path}:{line_of_key(path, where[-1])}: {field}: belongs in the rig file "
        f"({RIG_FIELDS[where]}), not the scene; a scene holds only what a simulation adds"
    )


@pytest.mark.parametrize(
    ("source", "rig_name", "field", "words"),
    [
        ({"irradiance_w_m2": 1.0}, "arch_point", "source.irradiance_w_m2", "is point"),
        ({"intensity_w_sr": 0.01}, "arch", "source.intensity_w_sr", "is collimated"),
    ],
    ids=["irradiance-for-a-point-source", "intensity-for-a-collimated-beam"],
)
def test_a_source_power_of_the_other_kind_is_one_line(
    arch_point: Rig,
    rigs: dict[str, Rig],
    tmp_path: Path,
    source: dict[str, float],
    rig_name: str,
    field: str,
    words: str,
) -> None:
    rig = {**rigs, "arch_point": arch_point}[rig_name]
    path = write(tmp_path, {**MATTE, "source": source})
    load_scene(path)  # alone, a scene does not know the rig's light
    with pytest.raises(ConfigError) as info:
        load_scene(path, rig)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:{line_of_key(path, field.split('.')[-1])}: {field}: ")
    assert f"the light of the rig file {rig.source} {words} (light.kind); expected" in message
    # Built in code, the scene is refused when it meets the rig.
    scene = Scene.model_validate({**MATTE, "source": source})
    with pytest.raises(ConfigError, match=f"^scene 'matte': {field}: the light of the rig file"):
        SceneOptics(scene, rig)


def test_shipped_scenes_fit_their_rigs(arch_point: Rig, rigs: dict[str, Rig]) -> None:
    for name in SHIPPED:
        rig = rig_of(name, rigs, arch_point)
        scene = load_scene(SCENES / f"{name}.yaml", rig)
        assert scene.source.kind == rig.source_kind


def test_missing_scene_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read the file"):
        load_scene(tmp_path / "none.yaml")


def rig_of(name: str, rigs: dict[str, Rig], arch_point: Rig) -> Rig:
    """The rig a shipped scene is simulated on (its light kind)."""
    return arch_point if name == "seed000_specular" else rigs["arch"]


@pytest.mark.parametrize("effects", ["own", "none", "faults"])
@pytest.mark.parametrize("name", SHIPPED)
def test_a_dumped_scene_reloads_equal_and_simulates_identically(
    tmp_path: Path, rigs: dict[str, Rig], arch_point: Rig, name: str, effects: str
) -> None:
    """A scene written out as YAML (as a user saves a tweaked scene) is read back by
    `load_scene` as the same scene, and a run in it draws the same numbers bit for bit;
    without effects it stays without (an empty set is written, not dropped), and
    injected faults come back as they were."""
    rig = rig_of(name, rigs, arch_point)
    scene = load_scene(SCENES / f"{name}.yaml", rig)
    if effects == "none":
        scene = scene.with_effects([])
    elif effects == "faults":
        scene = scene.with_faults(
            {"kind": "comm_error", "rate": 0.25}, {"kind": "motor_fault", "at": [2, 5]}
        )
    path = tmp_path / "dumped.yaml"
    path.write_text(yaml.safe_dump(scene.model_dump(mode="json"), sort_keys=False), "utf-8")
    reloaded = load_scene(path, rig)
    assert reloaded == scene
    assert reloaded.effects.names() == scene.effects.names()
    spec = PlanSpec.model_validate(
        {"name": "t", "sampling": {"strategy": "sobol", "target": 40}, "time_budget_s": 2}
    )
    plan = build(spec, rig)
    a, b = simulate(plan, scene), simulate(plan, reloaded)
    for field in ("read_back", "true", "settled_s", "end_s", "value", "std", "saturated"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)
