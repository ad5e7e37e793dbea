"""`synthesize` gives what a noise-free simulated run of the same plan measures;
`synthesize_adaptive` the two passes of an adaptive plan."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from gonio import brdf, params
from gonio.analysis.measured import Measured
from gonio.brdf.geometry import pair
from gonio.planner import adaptive
from gonio.rig.model import Rig
from studies.reconstruct.synthetic import synthesize, synthesize_adaptive
from tests.support.acquire import ARCH
from tests.support.runs import plan_spec, scene_spec, simulated_run

MATERIAL = {
    "name": "cook_torrance",
    "alpha": 0.1,
    "distribution": "ggx",
    "fresnel": "schlick",
    "f0": 0.04,
    "kd": 0.2,
}


@pytest.mark.parametrize("parametrization", ["hybrid", "rusinkiewicz"])
def test_the_samples_are_a_noise_free_run_of_the_same_plan(
    tmp_path: Path, parametrization: str
) -> None:
    scene = scene_spec("matte", material=MATERIAL, effects=[])
    run = Measured.from_run(
        simulated_run(tmp_path, plan_spec(150, parametrization=parametrization), scene)
    )
    study = synthesize(run.scene_truth(), run.rig, parametrization, True, 150, seed=3)
    assert len(study) == len(run) == 150
    # The run measures the plan's pairs in its travel order, each turned about the normal
    # as the rig reaches it (an isotropic plan): match them by their isotropic coordinates.
    p = params.get(parametrization)
    distance, index = cKDTree(p.forward_iso(study.wi, study.wo)).query(
        p.forward_iso(run.wi, run.wo)
    )
    assert np.all(distance < 1e-9)
    assert sorted(index.tolist()) == list(range(150))
    np.testing.assert_allclose(run.f, study.f[index], rtol=1e-9)


def test_an_adaptive_plan_is_its_survey_then_a_pass_denser_at_the_peak(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)
    truth = brdf.create(**MATERIAL).eval
    rig = Rig.from_yaml(ARCH)
    options = {"survey": 64, "model": "lambert+beckmann"}
    both = synthesize_adaptive(truth, rig, "rusinkiewicz", True, 400, seed=1, adaptive=options)
    survey = synthesize(truth, rig, "rusinkiewicz", True, 64, seed=1)
    uniform = synthesize(truth, rig, "rusinkiewicz", True, 400, seed=1)
    assert len(both) == 400 and both.source.startswith("synthetic adaptive")
    np.testing.assert_array_equal(both.wi[:64], survey.wi, strict=True)
    np.testing.assert_array_equal(both.wo[:64], survey.wo, strict=True)
    np.testing.assert_array_equal(both.f, truth(both.wi, both.wo), strict=True)

    def near_peak(m: Measured) -> float:
        return float(np.mean(pair(m.wi, m.wo).cos_theta_h() > np.cos(np.radians(10.0))))

    # GGX α 0.1 (Rusinkiewicz's uniform plans already give θh < 10° a fifth of their
    # samples): the adaptive plan gives it nearly half.
    assert near_peak(both) > 1.8 * near_peak(uniform) > 0


def test_sigma_is_relative_with_an_optional_absolute_part() -> None:
    truth = brdf.create(**MATERIAL).eval
    rig = Rig.from_yaml(ARCH)
    plain = synthesize(truth, rig, "rusinkiewicz", True, 40, seed=2)
    floored = synthesize(truth, rig, "rusinkiewicz", True, 40, seed=2, sigma_floor=1.0)
    np.testing.assert_allclose(plain.sigma, 0.01 * plain.f, rtol=1e-15)
    np.testing.assert_allclose(floored.sigma, 0.01 * (1.0 + floored.f), rtol=1e-15)
