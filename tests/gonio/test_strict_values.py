"""Values that are not meaningful are refused in one line naming the exact field, in the
user's words: yes/no for a number, integers beyond 64 bits, negative seeds, absurd
durations, reflectances above 1, materials that create energy, NaN parameters."""

from __future__ import annotations

import copy
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.config import ConfigError
from gonio.planner.files import load_plan_source
from gonio.rig.model import Rig
from gonio.scene import load_scene
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]
QUICK = yaml.safe_load((CONFIGS / "plans" / "quick.yaml").read_text())
MATTE = (CONFIGS / "scenes" / "matte.yaml").read_text()
MATTE_MATERIAL = (
    "{name: cook_torrance, alpha: 0.5, distribution: ggx, fresnel: schlick, f0: 0.04, kd: 0.6}"
)
ARCH = str(CONFIGS / "rigs" / "arch.yaml")


def plan_error(tmp_path: Path, change: Callable[[dict[str, Any]], object]) -> str:
    data = copy.deepcopy(QUICK)
    data["rig"] = ARCH
    change(data)
    path = tmp_path / "plan.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(ConfigError) as caught:
        load_plan_source(path)
    message = str(caught.value)
    assert "\n" not in message and len(message) < 300
    return message.split(": ", 1)[1]


@pytest.mark.parametrize(
    ("section", "key", "value", "expected"),
    [
        ("sampling", "target", True, "sampling.target: expected a number, not yes/no"),
        ("sampling", "seed", -1, "sampling.seed: Input should be greater than or equal to 0"),
        ("exposure", "averages", 1e23, "exposure.averages: expected an integer below 2**63"),
        ("exposure", "averages", 2**70, "exposure.averages: expected an integer below 2**63"),
        ("exposure", "seconds", 1e308, "exposure.seconds: Input should be less than or equal"),
        (None, "time_budget_s", 1e308, "time_budget_s: expected at most 1e+09 s"),
    ],
)
def test_plan_values(
    tmp_path: Path, section: str | None, key: str, value: object, expected: str
) -> None:
    def change(data: dict[str, Any]) -> None:
        (data[section] if section else data)[key] = value

    assert plan_error(tmp_path, change).startswith(expected)


def test_yes_is_refused_through_the_cli(tmp_path: Path, run_gonio: Gonio) -> None:
    path = tmp_path / "plan.yaml"
    text = (CONFIGS / "plans" / "quick.yaml").read_text().replace("target: 500", "target: yes")
    path.write_text(text.replace("../rigs/arch.yaml", ARCH))
    result = run_gonio("plan", str(path))
    assert result.returncode == 2
    assert "sampling.target: expected a number, not yes/no" in result.stderr


def scene_error(tmp_path: Path, material: str) -> str:
    path = tmp_path / "scene.yaml"
    text = MATTE.replace(MATTE_MATERIAL, material).replace("../rigs/", f"{CONFIGS}/rigs/")
    path.write_text(text)
    with pytest.raises(ConfigError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert "\n" not in message and len(message) < 240 + len(str(path)) + 40
    assert "(and " not in message and ".float" not in message
    return message.split(": ", 1)[1]


@pytest.mark.parametrize(
    ("material", "expected"),
    [
        ("{name: lambert, albedo: 5}", "material.albedo: a reflectance is at most 1"),
        ("{name: lambert, albedo: [0.5, 1.2, 0.5]}", "material.albedo: a reflectance is at most 1"),
        ("{name: lambert, albedo: yes}", "material.albedo: expected a number or a name, not yes"),
        ("{name: phong, n: 10, kd: 1.7}", "material.kd: a reflectance is at most 1"),
        ("{name: phong, n: 10, ks: 0.5, kd: 0.7}", "material.kd: kd + ks is 1.2; expected at most"),
        (
            "{name: cook_torrance, alpha: 0.5, fresnel: schlick, f0: 0.04, kd: 0.99}",
            "material.kd: kd + the Fresnel reflectance at normal incidence is 1.03",
        ),
        ("{name: cook_torrance, alpha: .nan, kd: 0.1}", "material.alpha: parameter alpha must be"),
        ("{name: cook_torrance, alpha: 0, kd: 0.1}", "material.alpha: parameter alpha must lie in"),
        ("{name: lambert, albedo: 0.5, bogus: 1}", "material.bogus: lambert: unknown parameter"),
        ("{name: nope}", "material.name: unknown BRDF model 'nope'"),
    ],
)
def test_material_values(tmp_path: Path, material: str, expected: str) -> None:
    assert scene_error(tmp_path, material).startswith(expected)


def test_a_huge_material_list_is_cut(tmp_path: Path) -> None:
    material = "{name: lambert, albedo: [" + ", ".join(["0.1"] * 5000) + "]}"
    assert scene_error(tmp_path, material).startswith("material.albedo: colour parameter")


def test_meaningful_materials_still_load(tmp_path: Path) -> None:
    for material in (
        "{name: lambert, albedo: 1}",
        "{name: phong, n: 10, ks: 0.4, kd: 0.6}",
        "{name: cook_torrance, alpha: 0.5, fresnel: schlick, f0: 0.04, kd: 0.96}",
    ):
        path = tmp_path / "scene.yaml"
        path.write_text(
            MATTE.replace(MATTE_MATERIAL, material).replace("../rigs/", f"{CONFIGS}/rigs/")
        )
        load_scene(path)


def test_yes_inside_a_mapping_of_numbers(tmp_path: Path) -> None:
    def counts(data: dict[str, Any]) -> None:
        data["sampling"]["counts"] = {"hbar": True}

    assert plan_error(tmp_path, counts).startswith("sampling.counts.hbar: expected a number")
    rig = tmp_path / "rig.yaml"
    text = (CONFIGS / "rigs" / "arch.yaml").read_text()
    rig.write_text(text.replace("light_elevation: [55, 85]", "light_elevation: [yes, 85]", 1))
    with pytest.raises(ConfigError) as caught:
        Rig.from_yaml(rig)
    assert ".ranges_deg.light_elevation.0: expected a number, not yes/no" in str(caught.value)
    line = next(n for n, t in enumerate(text.splitlines(), 1) if "light_elevation: [55" in t)
    assert str(caught.value).startswith(f"{rig}:{line}: ")
