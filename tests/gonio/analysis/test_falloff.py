"""The point source's spot fall-off divided out of a simulated run's samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.analysis import calibrate
from gonio.analysis.falloff import has_falloff
from gonio.planner import build, load_plan
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.workflows.simulate import Result, simulate_plan
from tests.support.runs import SCENES, plan_spec

NOISE = ["shot_noise", "read_noise", "dark_current", "quantization", "saturation"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory, arch_point: Rig) -> dict[str, Result]:
    """A 150-target plan on the point-source rig, measuring the specular test function
    with the sensor's noise, with and without the footprint effect."""
    path = Path(tmp_path_factory.mktemp("falloff")) / "plan.yaml"
    path.write_text(yaml.safe_dump(plan_spec(150, rig="arch_point", exposure_s=0.2)))
    spec, _ = load_plan(path)
    plan = build(spec, arch_point)
    scene = load_scene(SCENES / "seed000_specular.yaml", arch_point)
    return {
        name: simulate_plan(plan, scene.with_effects(effects), seed=7)
        for name, effects in (("footprint", ["footprint", *NOISE]), ("ideal", NOISE))
    }


def z_scores(result: Result, *, falloff: bool = True) -> np.ndarray:
    c = calibrate(result.run, falloff=falloff)
    return np.asarray(np.abs(c.brdf - result.truth) / c.sigma)


def test_with_the_footprint_the_corrected_errors_are_within_the_noise(
    runs: dict[str, Result],
) -> None:
    result = runs["footprint"]
    assert has_falloff(result.run)
    assert np.percentile(z_scores(result, falloff=False), 95) > 4
    assert np.percentile(z_scores(result), 95) <= 2


def test_without_the_footprint_effect_a_simulated_run_is_left_as_it_is(
    runs: dict[str, Result],
) -> None:
    result = runs["ideal"]
    assert not has_falloff(result.run)
    plain = calibrate(result.run, falloff=False)
    np.testing.assert_array_equal(result.brdf, plain.brdf)
    np.testing.assert_array_equal(result.sigma, plain.sigma)
