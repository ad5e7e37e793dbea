"""`synthesize` gives what a noise-free simulated run of the same plan measures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from gonio import params
from gonio.reconstruct.measured import Measured
from gonio.reconstruct.synthetic import synthesize
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
