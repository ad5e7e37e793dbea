"""Mistakes in a sweep file are one line naming the file, the line and the field, and
say what was expected; found when the file is read, before anything runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from gonio.config import ConfigError
from gonio.planner.schema import PlanSpec
from gonio.scene import load_scene
from gonio.tradeoff.grid import load_sweep
from tests.gonio.tradeoff.conftest import SMALL, write_sweep

AXES: dict[str, Any] = SMALL["axes"]


@pytest.mark.parametrize(
    ("changes", "where", "expected"),
    [
        ({"axes": {**AXES, "parametrization": ["hybird"]}}, "axes.parametrization.0",
         "unknown parametrization 'hybird'; expected one of"),
        ({"axes": {**AXES, "sampling": ["adaptiv"]}}, "axes.sampling.0",
         "unknown strategy 'adaptiv'; expected one of"),
        ({"axes": {**AXES, "samples": [100, 0]}}, "axes.samples.1", "expected a positive count"),
        ({"axes": {**AXES, "samples": [100, 100]}}, "axes.samples.1", "100 is given twice"),
        ({"axes": {**AXES, "exposure_s": [0.05, 100]}}, "axes.exposure_s.1",
         "outside the detector's exposure range [0.0001, 60] s"),
        ({"axes": {**AXES, "averages": [65]}}, "axes.averages.0",
         "the detector takes at most 64"),
        ({"axes": {**AXES, "velocity_scale": [-1]}}, "axes.velocity_scale.0",
         "expected a positive number"),
        ({"axes": {**AXES, "method": ["cubic"]}}, "axes.method.0",
         "unknown reconstruction method 'cubic'; expected one of naive"),
        ({"axes": {**AXES, "effects": [["shot_noise", "glare"]]}}, "axes.effects.0.1",
         "unknown effect 'glare'"),
        ({"axes": {**AXES, "effects": [{"without": ["glare"]}]}}, "axes.effects.0.without.0",
         "unknown effect 'glare'"),
        ({"axes": {**AXES, "effects": ["all"]}}, "axes.effects.0", "expected scene"),
        ({"axes": {**AXES, "exposure": [1]}}, "axes.exposure", "unknown field"),
        ({"axes": {k: v for k, v in AXES.items() if k != "samples"}}, "axes.samples",
         "Field required"),
        ({"exclude": [{"sample": 100}]}, "exclude.0.sample", "not an axis"),
        ({"warps": {"hybrid": {"theta_h": {"power": 2}}}}, "warps.hybrid.theta_h",
         "not a coordinate of isotropic hybrid"),
        ({"axes": {**AXES, "parametrization": ["spherical"]}}, "warps.spherical",
         "warped sampling in spherical needs a warp"),
        ({"metric": "rmse"}, "metric", "unknown metric 'rmse'"),
        ({"rig": "nowhere.yaml"}, None, "nowhere.yaml: cannot read the file"),
        ({"scenes": [SMALL["scenes"][0]] * 2}, "scenes.1", "another scene of the sweep is named"),
        ({"axes": {**AXES, "samples": list(range(1, 2000)), "averages": list(range(1, 60))}},
         "axes",
         "combinations; expected at most 100,000"),
        ({"exclude": [{"samples": 100}]}, "exclude", "every combination is excluded"),
    ],
    ids=lambda v: v if isinstance(v, str) else None,
)  # fmt: skip
def test_a_mistake_is_one_line_with_file_line_and_field(
    tmp_path: Path, changes: dict[str, Any], where: str | None, expected: str
) -> None:
    path = write_sweep(tmp_path, **changes)
    with pytest.raises(ConfigError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert "\n" not in message and len(message) < 600, message
    assert expected in message, message
    if where is not None:
        assert message.startswith(f"{path}:") and f": {where}: " in message, message
        assert 1 <= int(message.split(":")[1]) <= len(path.read_text().splitlines())


def test_a_warp_for_spherical_or_an_exclusion_makes_it_valid(tmp_path: Path) -> None:
    axes = {**AXES, "parametrization": ["spherical", "hybrid"]}
    warped = load_sweep(
        write_sweep(tmp_path, axes=axes, warps={"spherical": {"theta_i": {"power": 1.5}}})
    )
    assert len(warped.tasks) == 4
    plans = {(t.inputs["parametrization"], t.inputs["sampling"]): t.plan for t in warped.tasks}
    assert plans["spherical", "warped"]["sampling"]["warps"] == {"theta_i": {"power": 1.5}}
    assert plans["hybrid", "warped"]["sampling"]["warps"] == {"hbar": {"power": 2.0}}
    assert plans["hybrid", "sobol"]["sampling"]["warps"] == {}
    excluded = load_sweep(
        write_sweep(
            tmp_path, axes=axes, exclude=[{"parametrization": "spherical", "sampling": "warped"}]
        )
    )
    assert [(t.inputs["parametrization"], t.inputs["sampling"]) for t in excluded.tasks] == [
        ("spherical", "sobol"),
        ("hybrid", "sobol"),
        ("hybrid", "warped"),
    ]


def test_the_shipped_quick_sweep_has_at_least_200_combinations() -> None:
    sweep = load_sweep(Path(__file__).resolve().parents[3] / "configs" / "sweeps" / "quick.yaml")
    assert len(sweep.tasks) >= 200
    assert len({t.id for t in sweep.tasks}) == len(sweep.tasks)
    assert yaml.safe_load(sweep.path.read_text())["name"] == sweep.spec.name


def test_the_parametrization_axis_defaults_to_the_planners(tmp_path: Path) -> None:
    axes = {k: v for k, v in AXES.items() if k != "parametrization"}
    sweep = load_sweep(write_sweep(tmp_path, axes=axes))
    default = PlanSpec.model_fields["parametrization"].default
    assert {t.inputs["parametrization"] for t in sweep.tasks} == {default} == {"rusinkiewicz"}


def test_the_lockin_sweep_compares_a_lockin_with_a_dc_photodiode_at_equal_plans() -> None:
    sweep = load_sweep(Path(__file__).resolve().parents[3] / "configs" / "sweeps" / "lockin.yaml")
    kinds = [load_scene(scene.path).detector.kind for scene in sweep.scenes]
    assert kinds == ["adc", "lockin"] and len(sweep.tasks) == 16
