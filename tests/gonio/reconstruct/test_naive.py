"""The naive reference reconstruction: exact where it should be, converging on a smooth
BRDF as the samples grow, with the interface the evaluation uses."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.analysis.measured import Measured
from gonio.errors import GonioError
from gonio.reconstruct import testset
from gonio.reconstruct.metrics import scores
from gonio.reconstruct.naive import MAX_NODES, NaiveReconstruction, default_nodes
from gonio.rig.model import Rig
from gonio.types import FloatArray


def smooth(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """An isotropic, reciprocal, smooth BRDF (sr⁻¹)."""
    mirror = wi * np.array([-1.0, -1.0, 1.0])
    return 0.2 + 0.5 * np.sum(mirror * wo, axis=-1) ** 2 + wi[..., 2] * wo[..., 2]


def measured_of(
    rig: Rig, n: int, f: object = smooth, *, isotropic: bool = True, seed: int = 7
) -> Measured:
    """``n`` samples of ``f`` at measurable pairs (a test set of another seed)."""
    pairs = testset.draw(rig, isotropic=isotropic, size=n, seed=seed)
    values = np.asarray(f(pairs.wi, pairs.wo))  # type: ignore[operator]
    return Measured(
        wi=pairs.wi,
        wo=pairs.wo,
        f=values,
        sigma=np.zeros_like(values),
        parametrization="hybrid",
        isotropic=isotropic,
        rig=rig,
        scene_text=None,
        band="rgb" if values.ndim == 2 else "luminance",
        source="synthetic",
    )


@pytest.fixture(scope="module")
def arch(rigs: dict[str, Rig]) -> Rig:
    return rigs["arch"]


@pytest.fixture(scope="module")
def queries(arch: Rig) -> testset.TestSet:
    return testset.draw(arch, isotropic=True, size=4000, seed=1)


def test_the_error_shrinks_as_the_samples_grow(arch: Rig, queries: testset.TestSet) -> None:
    truth = smooth(queries.wi, queries.wo)
    errors = []
    for n in (200, 2000, 20000):
        candidate = NaiveReconstruction(measured_of(arch, n)).eval(queries.wi, queries.wo)
        errors.append(scores(candidate, truth, queries.wi[:, 2]).log_rmse)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.35 * errors[0]
    assert errors[2] < 0.01  # log(1 + f) to 1 % on a smooth BRDF with 20 000 samples


def test_a_constant_brdf_comes_back_exactly_everywhere(arch: Rig) -> None:
    measured = measured_of(arch, 300, lambda wi, wo: np.full(len(wi), 0.25))
    naive = NaiveReconstruction(measured)
    rng = np.random.default_rng(4)
    wi = testset.uniform_cap(rng, 1000, np.pi / 2)  # the whole hemisphere, unmeasured too
    wo = testset.uniform_cap(rng, 1000, np.pi / 2)
    np.testing.assert_allclose(naive.eval(wi, wo), 0.25, rtol=1e-14)


def test_supported_is_where_the_nearest_node_has_samples(arch: Rig) -> None:
    measured = measured_of(arch, 2000)
    near_normal = (measured.wi[:, 2] > np.cos(0.35)) & (measured.wo[:, 2] > np.cos(0.35))
    measured = measured.subset(near_normal)
    naive = NaiveReconstruction(measured, nodes=7)
    assert naive.supported(measured.wi, measured.wo).all()
    rng = np.random.default_rng(4)
    wi, wo = testset.uniform_cap(rng, 5000, np.pi / 2), testset.uniform_cap(rng, 5000, np.pi / 2)
    inside = naive.supported(wi, wo)
    assert not inside[(wi[:, 2] < 0.5) & (wo[:, 2] < 0.5)].any()  # both beyond 60°


def test_rgb_reconstructs_each_channel_as_one(arch: Rig, queries: testset.TestSet) -> None:
    def rgb(wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.stack([smooth(wi, wo), 2 * smooth(wi, wo), np.full(len(wi), 0.1)], -1)

    colour = NaiveReconstruction(measured_of(arch, 500, rgb)).eval(queries.wi, queries.wo)
    green = NaiveReconstruction(measured_of(arch, 500, lambda wi, wo: 2 * smooth(wi, wo)))
    assert colour.shape == (len(queries), 3)
    np.testing.assert_allclose(colour[:, 1], green.eval(queries.wi, queries.wo), rtol=1e-13)
    np.testing.assert_allclose(colour[:, 2], 0.1, rtol=1e-13)


def test_an_anisotropic_run_uses_all_four_coordinates(arch: Rig) -> None:
    def tilted(wi: FloatArray, wo: FloatArray) -> FloatArray:
        return 0.3 + 0.2 * wi[..., 0] ** 2 + 0.2 * wo[..., 0] ** 2

    measured = measured_of(arch, 4000, tilted, isotropic=False)
    naive = NaiveReconstruction(measured)
    assert naive.nodes == default_nodes(4000, 4) == 8
    q = testset.draw(arch, isotropic=False, size=2000, seed=2)
    rotated = q.wi[:, [1, 0, 2]], q.wo[:, [1, 0, 2]]  # x ↔ y: changes f, not an iso model
    error = scores(naive.eval(q.wi, q.wo), tilted(q.wi, q.wo), q.wi[:, 2]).log_rmse
    wrong = scores(naive.eval(*rotated), tilted(q.wi, q.wo), q.wi[:, 2]).log_rmse
    assert error is not None and wrong is not None and error < 0.5 * wrong


def test_the_parametrization_and_grid_can_be_chosen(arch: Rig, queries: testset.TestSet) -> None:
    measured = measured_of(arch, 2000)
    naive = NaiveReconstruction(measured, parametrization="spherical", nodes=10)
    assert naive.parametrization.name == "spherical" and naive.nodes == 10
    error = scores(
        naive.eval(queries.wi, queries.wo), smooth(queries.wi, queries.wo), queries.wi[:, 2]
    )
    assert error.log_rmse is not None and error.log_rmse < 0.05
    assert naive.eval(queries.wi[:6].reshape(2, 3, 3), queries.wo[:6].reshape(2, 3, 3)).shape == (
        2,
        3,
    )
    with pytest.raises(ValueError, match="at least 2 nodes"):
        NaiveReconstruction(measured, nodes=1)
    empty = measured.subset(slice(0, 0))
    with pytest.raises(GonioError, match="synthetic: no sample to reconstruct from"):
        NaiveReconstruction(empty)


def test_default_nodes_are_about_one_per_sample() -> None:
    assert default_nodes(1000, 3) == 10
    assert default_nodes(3, 3) == 2
    assert default_nodes(10**12, 3) == MAX_NODES
