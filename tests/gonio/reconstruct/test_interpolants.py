"""The interpolants: exact on affine data, a point location that agrees with scipy's,
barycentric transforms and coordinates that agree with scipy's public ones."""

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


def _vertex_weights(simplices: np.ndarray, s: np.ndarray, c: np.ndarray, n: int) -> np.ndarray:
    """Barycentric coordinates (M, d + 1) in simplices s (M,) as weights of the n points
    (M, n): a query on a shared face has the same weights in every simplex holding it."""
    w = np.zeros((len(s), n))
    w[np.arange(len(s))[:, None], simplices[s]] = c
    return w


def _scipy_weights(tri: Delaunay, queries: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """scipy's public answer: ``find_simplex`` and ``transform``, as vertex weights."""
    s = tri.find_simplex(queries)
    inside = s >= 0
    t = tri.transform[s[inside]]
    d = queries.shape[1]
    c = np.einsum("mij,mj->mi", t[:, :d, :], queries[inside] - t[:, d, :])
    c = np.concatenate([c, 1.0 - c.sum(axis=1, keepdims=True)], axis=1)
    return s, _vertex_weights(tri.simplices, s[inside], c, tri.npoints)


def _inside_on_edges_and_outside(points: np.ndarray, tri: Delaunay, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    d = points.shape[1]
    corners = tri.simplices[rng.integers(0, tri.nsimplex, 500)]
    t = rng.random((500, 1))
    on_edges = t * points[corners[:, 0]] + (1.0 - t) * points[corners[:, 1]]
    corners[:, 0] = corners[:, 1]  # and the vertices themselves
    return np.concatenate(
        [
            rng.uniform(0.1, 0.9, (1000, d)),
            on_edges,
            points[corners[:100, 0]],
            rng.uniform(-0.5, 1.5, (500, d)),  # most of them outside the hull
        ]
    )


@pytest.mark.parametrize("d", [2, 3, 4])
def test_barycentric_coordinates_agree_with_scipys_public_find_simplex_and_transform(
    d: int,
) -> None:
    """The walk (and the search it falls back on) against ``find_simplex`` + ``transform``
    of another triangulation of the same points: the same weights of the points within
    1e-12 inside, on edges and at vertices, and the same queries outside, but for a
    point on the hull that scipy may call outside (held here within rounding)."""
    points = np.random.default_rng(20 + d).random((200, d))
    linear = Linear(points, points[:, :1])
    tri = Delaunay(points)
    queries = _inside_on_edges_and_outside(points, tri, seed=d)
    nearest = np.argmin(((queries[:, None, :] - points[None]) ** 2).sum(-1), axis=1)
    reference, expected = _scipy_weights(tri, queries)
    assert 0.1 < (reference < 0).mean() < 0.4
    for found in (linear.locate(queries, nearest), linear.search(queries)):
        assert (found[reference >= 0] >= 0).all()
        on_hull = (found >= 0) & (reference < 0)
        assert on_hull.sum() <= 2
        assert (linear._barycentric(queries[on_hull], found[on_hull]) >= -1e-12).all()
        inside = reference >= 0
        c = linear._barycentric(queries[inside], found[inside])
        got = _vertex_weights(linear.tri.simplices, found[inside], c, len(points))
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_the_search_finds_a_simplex_holding_each_query_among_flat_simplices() -> None:
    rng = np.random.default_rng(1)
    half = rng.random((300, 3))
    points = np.concatenate([half, half * [-1, 1, 1]])  # cocircular quadruples: flat simplices
    linear = Linear(points, points[:, :1])
    assert np.isnan(linear.transform[:, 0, 0]).any()
    queries = rng.uniform([-1.2, -0.1, -0.1], [1.2, 1.1, 1.1], (1000, 3))
    found = linear.search(queries)
    reference, expected = _scipy_weights(Delaunay(points), queries)
    np.testing.assert_array_equal(found < 0, reference < 0)
    inside = found >= 0
    c = linear._barycentric(queries[inside], found[inside])
    assert (c >= -1e-9).all()
    got = _vertex_weights(linear.tri.simplices, found[inside], c, len(points))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)


def test_rbf_passes_through_its_data() -> None:
    rng = np.random.default_rng(3)
    points = rng.random((400, 3))
    table = np.stack([np.sin(3 * points[:, 0]), points[:, 1] ** 2], axis=1)
    out, defined = Rbf(points, table)(points[:50], np.arange(50))
    assert defined.all()
    np.testing.assert_allclose(out, table[:50], rtol=0, atol=1e-8)
