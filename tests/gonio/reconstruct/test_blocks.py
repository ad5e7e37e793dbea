"""A reconstruction evaluates its pairs in blocks (`EVALUATION_BLOCK`): each pair's value,
σ and support are its own, bit for bit whatever the block size and whichever pairs share
its batch — the walk leaves a flat simplex by a face chosen from the simplex and the step,
not from the query's place in the batch."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.analysis.measured import Measured
from gonio.brdf.base import BRDF
from gonio.reconstruct import result
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.interpolants import Linear
from gonio.reconstruct.result import Reconstruction
from gonio.rig.model import Rig
from gonio.types import FloatArray
from studies.reconstruct.synthetic import synthesize


def pairs(seed: int, n: int, measured: Measured) -> tuple[FloatArray, FloatArray]:
    """``n`` pairs uniform over the sphere (a quarter below the horizon), then the
    first ``n`` measured pairs themselves (queries on the triangulation's vertices)."""
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(2, n, 3))
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    w[..., 2] = np.abs(w[..., 2]) * np.where(rng.random((2, n)) < 0.87, 1.0, -1.0)
    return np.concatenate([w[0], measured.wi[:n]]), np.concatenate([w[1], measured.wo[:n]])


@pytest.fixture(scope="module")
def grid_iso(arch: Rig, matte: BRDF) -> Measured:
    """A grid plan's samples: cocircular points, hence flat Delaunay simplices."""
    return synthesize(matte.eval, arch, "hybrid", True, 0, grid=10)


@pytest.fixture(scope="module")
def reconstructions(matte_iso: Measured, grid_iso: Measured) -> dict[str, Reconstruction]:
    return {
        "linear": reconstruct(matte_iso, extrapolate="nearest"),
        "linear on a grid": reconstruct(grid_iso),
        "grid": reconstruct(grid_iso, method="grid"),
    }


@settings(max_examples=12, deadline=None)
@given(
    name=st.sampled_from(["linear", "linear on a grid", "grid"]),
    size=st.integers(1, 700),
    seed=st.integers(0, 2**32 - 1),
)
def test_blocks_of_any_size_give_what_one_call_gives(
    reconstructions: dict[str, Reconstruction],
    matte_iso: Measured,
    grid_iso: Measured,
    name: str,
    size: int,
    seed: int,
) -> None:
    r = reconstructions[name]
    # blocks of a few pairs on fewer pairs: as many blocks, a fraction of the calls
    count = 1500 if size >= 100 else 15 * size
    wi, wo = pairs(seed, count, grid_iso if "grid" in name else matte_iso)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(result, "EVALUATION_BLOCK", 10**9)
        whole = r.evaluate(wi, wo)
        patch.setattr(result, "EVALUATION_BLOCK", size)
        blocked = r.evaluate(wi, wo)
    for got, expected in zip(blocked, whole, strict=True):
        assert got.dtype == expected.dtype and got.tobytes() == expected.tobytes()
    assert whole[2].any() and not whole[2].all()


def test_the_walk_out_of_flat_simplices_does_not_depend_on_the_batch() -> None:
    # Mirrored points make cocircular quadruples (flat simplices); the points themselves
    # as queries lie on many simplices at once, where the path decides which is found.
    # Every walk starts at point 0's simplex: long walks, across many flat simplices.
    rng = np.random.default_rng(1)
    half = rng.random((300, 3))
    points = np.concatenate([half, half * [-1, 1, 1]])
    linear = Linear(points, points[:, :1])
    assert np.isnan(linear.transform[:, 0, 0]).any()
    queries = np.concatenate([points, rng.uniform([-0.9, 0.1, 0.1], [0.9, 0.9, 0.9], (600, 3))])
    nearest = np.zeros(len(queries), dtype=np.intp)
    found = linear.locate(queries, nearest)
    order = rng.permutation(len(queries))
    shuffled = np.empty_like(found)
    shuffled[order] = linear.locate(queries[order], nearest[order])
    assert np.array_equal(found, shuffled)
    alone = np.concatenate(
        [linear.locate(queries[k : k + 7], nearest[k : k + 7]) for k in range(0, len(queries), 7)]
    )
    assert np.array_equal(found, alone)
