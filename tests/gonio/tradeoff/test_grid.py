"""A sweep's combinations: one per point of the axes' product less the exclusions, each
named by a hash of its inputs (stable across readings, changed by any input, kept when
other values are added to an axis: a grown sweep reuses what it finished), its seeds
drawn from that hash; the effects each models; the velocity-scaled rigs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio.config import ConfigError
from gonio.rig.model import Rig
from gonio.tradeoff.grid import load_sweep, resolved_effects, scaled_rig
from gonio.tradeoff.spec import Without
from tests.conftest import CONFIGS
from tests.gonio.tradeoff.conftest import SMALL, write_sweep

AXES = SMALL["axes"]


def test_ids_are_stable_distinct_and_seed_the_combination(tmp_path: Path) -> None:
    path = write_sweep(tmp_path, axes={**AXES, "exposure_s": [0.02, 0.1]}, replicates=2)
    first, again = load_sweep(path), load_sweep(path)
    assert [t.id for t in first.tasks] == [t.id for t in again.tasks]
    assert len({t.id for t in first.tasks}) == len(first.tasks) == 16
    for task in first.tasks:
        assert task.plan["sampling"]["seed"] == task.inputs["plan_seed"]
        assert task.run_seed == task.inputs["run_seed"]
    assert len({t.run_seed for t in first.tasks}) == 16
    assert [t.inputs["replicate"] for t in first.tasks[:4]] == [0, 1, 0, 1]


def test_adding_a_value_keeps_the_ids_of_the_others(tmp_path: Path) -> None:
    small = load_sweep(write_sweep(tmp_path, "a"))
    grown = load_sweep(write_sweep(tmp_path, "b", axes={**AXES, "samples": [100, 200]}))
    assert {t.id for t in small.tasks} < {t.id for t in grown.tasks}
    renamed = load_sweep(write_sweep(tmp_path, "c", name="other-name"))
    assert [t.id for t in renamed.tasks] == [t.id for t in small.tasks]


def test_any_input_changes_the_id(tmp_path: Path) -> None:
    base = {t.id for t in load_sweep(write_sweep(tmp_path, "a")).tasks}
    scene = tmp_path / "scene.yaml"
    scene.write_text((CONFIGS / "scenes" / "matte.yaml").read_text() + "# edited\n")
    for changes in (
        {"scenes": [str(scene)]},
        {"seed": 1},
        {"evaluation": {"pairs": 2001}},
        {"plan": {"kicks": 21}},
        {
            "warps": {"hybrid": {"hbar": {"power": 3}}},
            "axes": {**AXES, "parametrization": ["hybrid"], "sampling": ["warped"]},
        },
    ):
        changed = load_sweep(write_sweep(tmp_path, "b", **changes))
        assert not base & {t.id for t in changed.tasks}, changes


def test_the_effects_a_combination_models(tmp_path: Path) -> None:
    glossy = str(CONFIGS / "scenes" / "glossy_metal.yaml")
    sweep = load_sweep(write_sweep(tmp_path, scenes=[glossy]))
    scene = sweep.scenes[0]
    assert scene.effects["aperture_integration"] == {"order": 6}
    assert resolved_effects("scene", scene) == scene.effects
    assert resolved_effects("none", scene) == {}
    assert resolved_effects(["shot_noise", "stray_light"], scene) == {
        "shot_noise": {},
        "stray_light": {},
    }
    without = resolved_effects(Without(without=["shot_noise", "footprint"]), scene)
    assert set(without) == set(scene.effects) - {"shot_noise", "footprint"}
    effects = [["aperture_integration"], {"without": ["saturation"]}, "none"]
    labels = {
        t.inputs["effects"]
        for t in load_sweep(
            write_sweep(tmp_path, scenes=[glossy], axes={**AXES, "effects": effects})
        ).tasks
    }
    assert labels == {"aperture_integration", "without:saturation", "none"}


def test_an_effect_without_its_parameters_is_one_line(tmp_path: Path) -> None:
    matte = str(CONFIGS / "scenes" / "matte.yaml")
    path = write_sweep(
        tmp_path, scenes=[matte], axes={**AXES, "effects": ["none", ["stray_light"]]}
    )
    with pytest.raises(ConfigError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert "\n" not in message
    assert "axes.effects[1]" in message or "axes.effects.1" in message, message
    assert "stray_light.power_w: field required" in message, message


@pytest.mark.parametrize("scale", [0.25, 0.7, 2.0, 3.9])
def test_a_scaled_rig_moves_in_1_over_scale_of_the_time(scale: float) -> None:
    rig = Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")
    scaled = Rig.from_yaml("scaled.yaml", raw=scaled_rig(rig, scale))
    rng = np.random.default_rng(0)
    p, q = rng.uniform(-1.0, 1.0, (2, 50, len(rig.axes)))
    np.testing.assert_allclose(scaled.travel.time(p, q), rig.travel.time(p, q) / scale, rtol=1e-12)
    assert scaled_rig(rig, 1.0) is rig.text
