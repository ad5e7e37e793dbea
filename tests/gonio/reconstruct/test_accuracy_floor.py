"""The accuracy floor: on noise-free samples of a uniform plan, in every
parametrization, the reconstruction is at least as accurate as the naive grid a user
would write in an afternoon (studies/accuracy.py has the full table)."""

from __future__ import annotations

import pytest

from gonio import brdf, params
from gonio.reconstruct import testset
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.evaluate import evaluate
from gonio.reconstruct.naive import NaiveReconstruction
from gonio.rig.model import Rig
from studies.reconstruct.synthetic import synthesize

#: GGX α = 0.1, F0 = 0.04 over a Lambertian base kd = 0.2 (the issue's material).
MATERIAL = brdf.create(
    "cook_torrance", alpha=0.1, distribution="ggx", fresnel="schlick", f0=0.04, kd=0.2
)


@pytest.fixture(scope="module")
def pairs(arch: Rig) -> testset.TestSet:
    return testset.draw(arch, isotropic=True, size=5000)


@pytest.mark.parametrize(
    ("method", "parametrization"),
    [*(("linear", name) for name in params.names()), ("rbf", "hybrid")],
)
def test_no_worse_than_the_naive_grid(
    arch: Rig, pairs: testset.TestSet, parametrization: str, method: str
) -> None:
    samples = synthesize(MATERIAL.eval, arch, parametrization, True, 2000, seed=3)

    def log_rmse(candidate: object) -> float:
        result = evaluate(candidate, MATERIAL.eval, arch, isotropic=True, test_set=pairs)  # type: ignore[arg-type]
        value = result.regions["all"].scores.log_rmse
        assert value is not None
        return value

    naive = log_rmse(NaiveReconstruction(samples))
    ours = log_rmse(reconstruct(samples, method=method, extrapolate="nearest"))
    assert ours <= naive, (parametrization, method, ours, naive)
