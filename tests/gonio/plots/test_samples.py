"""The samples' coverage: their coordinates in the plan's parametrization, coloured by
log10 f or by the residual in σ against a truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio import params
from gonio.errors import GonioError
from gonio.plots import samples
from gonio.reconstruct import testset
from gonio.rig.model import Rig
from tests.support.figures import Lobe


@pytest.fixture(scope="module")
def pairs(rigs: dict[str, Rig]) -> testset.TestSet:
    return testset.draw(rigs["arch"], isotropic=True, size=200, seed=5)


def test_coloured_by_value(pairs: testset.TestSet) -> None:
    f = Lobe().eval(pairs.wi, pairs.wo)
    f[0] = 0.0  # below the floor: coloured as the floor, not −inf
    data = samples.coverage(
        (pairs.wi, pairs.wo, f, 0.1 * f), "hybrid", isotropic=True, theta_max=math.radians(80.0)
    )
    np.testing.assert_array_equal(data.coords, params.get("hybrid").forward_iso(pairs.wi, pairs.wo))
    assert data.names == ("hbar", "k", "phi_k_minus_phi_h")
    np.testing.assert_array_equal(data.colour[1:], np.log10(f[1:]))
    assert data.colour[0] == math.log10(samples.FLOOR)


def test_coloured_by_residual_in_sigma(pairs: testset.TestSet) -> None:
    lobe = Lobe()
    t = lobe.eval(pairs.wi, pairs.wo)
    sigma = np.full(len(t), 0.02)
    f = t + sigma * np.linspace(-3.0, 3.0, len(t))
    data = samples.coverage(
        (pairs.wi, pairs.wo, f, sigma),
        "rusinkiewicz",
        isotropic=False,
        theta_max=1.0,
        colour_by="residual",
        truth=lobe.eval,
    )
    np.testing.assert_allclose(data.colour, np.linspace(-3.0, 3.0, len(t)), atol=1e-12)
    np.testing.assert_array_equal(
        data.coords, params.get("rusinkiewicz").forward(pairs.wi, pairs.wo)
    )
    assert len(data.names) == 4


def test_a_residual_needs_a_truth_and_a_colour_must_be_known(pairs: testset.TestSet) -> None:
    args = ((pairs.wi, pairs.wo, np.ones(len(pairs)), np.ones(len(pairs))), "hybrid")
    with pytest.raises(GonioError, match="--colour residual needs a truth"):
        samples.coverage(*args, isotropic=True, theta_max=1.0, colour_by="residual")
    with pytest.raises(GonioError, match="--colour hue: expected one of value, residual"):
        samples.coverage(*args, isotropic=True, theta_max=1.0, colour_by="hue")


def test_without_sigma_the_residual_is_relative(pairs: testset.TestSet) -> None:
    """A noise-free simulation has σ = 0: no residual in σ, and no division by 0."""
    t = Lobe().eval(pairs.wi, pairs.wo)
    f = 1.1 * t
    sigma = np.where(np.arange(len(t)) % 2 == 0, 0.0, 0.1)
    data = samples.coverage(
        (pairs.wi, pairs.wo, f, sigma),
        "hybrid",
        isotropic=True,
        theta_max=1.0,
        colour_by="residual",
        truth=Lobe().eval,
    )
    np.testing.assert_allclose(data.colour, 0.1, rtol=1e-12)
    assert data.colour_label.startswith("relative residual")
