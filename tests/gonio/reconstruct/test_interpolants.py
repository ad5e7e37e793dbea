"""The interpolants: exact on affine data, a point location that agrees with scipy's,
barycentric transforms that agree with scipy's."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from gonio.reconstruct.interpolants import Linear, Rbf, barycentric_transforms


@pytest.mark.parametrize("d", [3, 4])
def test_linear_reproduces_affine_data_exactly(d: int) -> None:
    rng = np.random.default_rng(d)
    points = rng.random((600, d))
    a, b = rng.normal(size=(d, 2)), rng.normal(size=2)
    linear = Linear(points, points @ a + b)
    queries = rng.uniform(0.2, 0.8, (2000, d))
    nearest = np.argmin(((queries[:, None, :] - points[None]) ** 2).sum(-1), axis=1)
    out, defined = linear(queries, nearest)
    assert defined.all()
    np.testing.assert_allclose(out, queries @ a + b, rtol=0, atol=1e-12)


def test_linear_is_undefined_outside_the_hull() -> None:
    points = np.random.default_rng(0).random((200, 3))
    linear = Linear(points, points[:, :1])
    out, defined = linear(np.array([[1.5, 0.5, 0.5], [-0.2, 0.5, 0.5]]), np.array([0, 1]))
    assert not defined.any()
    assert np.isnan(out).all()


def test_the_walk_finds_the_simplex_scipy_finds_even_among_flat_simplices() -> None:
    # Mirrored points make cocircular quadruples: flat simplices the walk must leave.
    rng = np.random.default_rng(1)
    half = rng.random((300, 3))
    points = np.concatenate([half, half * [-1, 1, 1]])
    linear = Linear(points, points[:, :1])
    queries = rng.uniform([-0.9, 0.1, 0.1], [0.9, 0.9, 0.9], (1000, 3))
    nearest = np.argmin(((queries[:, None, :] - points[None]) ** 2).sum(-1), axis=1)
    found = linear.locate(queries, nearest)
    reference = Delaunay(points).find_simplex(queries)
    same = found == reference
    # Where they differ the query is on a shared face: both simplices contain it.
    other = ~same
    for s in (found[other], reference[other]):
        c = linear._barycentric(queries[other], s)
        assert (c >= -1e-9).all()
    assert same.mean() > 0.99


def test_batched_barycentric_transforms_match_scipys() -> None:
    tri = Delaunay(np.random.default_rng(2).random((300, 3)))
    np.testing.assert_allclose(
        barycentric_transforms(tri.points, tri.simplices), tri.transform, rtol=0, atol=1e-7
    )


def test_rbf_passes_through_its_data() -> None:
    rng = np.random.default_rng(3)
    points = rng.random((400, 3))
    table = np.stack([np.sin(3 * points[:, 0]), points[:, 1] ** 2], axis=1)
    out, defined = Rbf(points, table)(points[:50], np.arange(50))
    assert defined.all()
    np.testing.assert_allclose(out, table[:50], rtol=0, atol=1e-8)
