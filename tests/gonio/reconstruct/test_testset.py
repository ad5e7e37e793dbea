"""The test set: reproducible, measurable by the rig, uniform in solid angle."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from gonio.errors import GonioError
from gonio.reconstruct import testset
from gonio.rig.model import Rig


@pytest.fixture(scope="module")
def arch(rigs: dict[str, Rig]) -> Rig:
    return rigs["arch"]


def test_the_same_seed_gives_the_same_pairs_bit_for_bit(arch: Rig) -> None:
    a = testset.draw(arch, isotropic=True, size=3000)
    b = testset.draw(arch, isotropic=True, size=3000)
    c = testset.draw(arch, isotropic=True, size=3000, seed=15)
    assert len(a) == 3000 and a.seed == testset.DEFAULT_SEED and a.drawn >= 3000
    assert np.array_equal(a.wi, b.wi) and np.array_equal(a.wo, b.wo)
    assert not np.array_equal(a.wi, c.wi)


@pytest.mark.parametrize("isotropic", [True, False])
def test_every_pair_is_measurable(arch: Rig, isotropic: bool) -> None:
    pairs = testset.draw(arch, isotropic=isotropic, size=2000)
    ok, _ = arch.reachable(pairs.wi, pairs.wo, isotropic=isotropic)
    assert ok.all()
    np.testing.assert_allclose(np.linalg.norm(pairs.wi, axis=1), 1.0, atol=1e-15)
    assert np.all(np.minimum(pairs.wi[:, 2], pairs.wo[:, 2]) >= math.cos(arch.theta_max))


def test_directions_are_uniform_in_solid_angle_over_the_cap() -> None:
    theta_max = math.radians(80.0)
    w = testset.uniform_cap(np.random.default_rng(5), 20000, theta_max)
    # uniform in solid angle ⟺ cos θ uniform on [cos θmax, 1] and φ uniform on [0, 2π)
    lo = math.cos(theta_max)
    assert stats.kstest(w[:, 2], stats.uniform(lo, 1 - lo).cdf).pvalue > 0.01
    phi = np.arctan2(w[:, 1], w[:, 0]) % (2 * math.pi)
    assert stats.kstest(phi, stats.uniform(0, 2 * math.pi).cdf).pvalue > 0.01
    # and not uniform in θ, which a wrong draw would give
    theta = np.arccos(w[:, 2])
    assert stats.kstest(theta, stats.uniform(0, theta_max).cdf).pvalue < 1e-6


def test_the_set_keeps_the_solid_angle_law_inside_what_the_rig_measures(arch: Rig) -> None:
    """Dropping unmeasurable pairs must not bias the rest: the set's cos θi follows that
    of an independent uniform draw kept by the same rule."""
    pairs = testset.draw(arch, isotropic=True, size=5000)
    rng = np.random.default_rng(99)
    wi = testset.uniform_cap(rng, 12000, arch.theta_max)
    wo = testset.uniform_cap(rng, 12000, arch.theta_max)
    ok, _ = arch.reachable(wi, wo, isotropic=True)
    assert stats.ks_2samp(pairs.wi[:, 2], wi[ok, 2]).pvalue > 0.01
    assert stats.ks_2samp(pairs.wo[:, 2], wo[ok, 2]).pvalue > 0.01


def test_a_rig_that_measures_almost_nothing_is_an_error() -> None:
    class Blind:
        theta_max = 1.0
        spec = SimpleNamespace(name="blind")

        def reachable(self, wi: np.ndarray, wo: np.ndarray, *, isotropic: bool) -> tuple:
            return np.zeros(len(wi), dtype=bool), None

    with pytest.raises(GonioError, match="measures only 0 of"):
        testset.draw(Blind(), isotropic=True, size=10)  # type: ignore[arg-type]
    with pytest.raises(GonioError, match="at least one pair"):
        testset.draw(Blind(), isotropic=True, size=0)  # type: ignore[arg-type]
