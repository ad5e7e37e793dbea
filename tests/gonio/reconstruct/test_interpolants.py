"""The interpolants: exact on affine data, a point location that agrees with scipy's,
barycentric transforms and coordinates that agree with scipy's public ones."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

from gonio.reconstruct.interpolants import (
    Linear,
    Rbf,
    barycentric_transforms,
    most_regular,
    transforms_and_regularity,
)


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


def _grid_and_seam_copies() -> np.ndarray:
    """Cell centres of a 10³ grid and their mirror images across z = 0 near it (the seam
    copies of a grid run): cospherical points, flat simplices and slivers everywhere."""
    g = (np.arange(10) + 0.5) / 10
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.concatenate([grid, grid[grid[:, 2] < 0.2] * [1, 1, -1]])


def test_the_walk_arrives_among_a_grids_flat_simplices_and_searches_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Inside the hull every query arrives (on the grid's planes too, where the flat
    simplices are), outside it the walk or the hull's facets say so: no query is left to
    the search over every simplex. The answers are scipy's (a query on a flat
    simplex's plane may take the other side's simplex: both hold it)."""
    points = _grid_and_seam_copies()
    linear = Linear(points, points[:, :1])
    assert linear.flat.mean() > 0.1

    def refuse(x: np.ndarray) -> np.ndarray:
        raise AssertionError(f"{len(x)} queries left to the search")

    monkeypatch.setattr(linear, "search", refuse)
    rng = np.random.default_rng(4)
    queries = rng.uniform(-0.3, 1.3, (4000, 3))
    queries[:1500, rng.integers(0, 3)] = (rng.integers(0, 10, 1500) + 0.5) / 10
    nearest = np.argmin(((queries[:, None, :] - points[None]) ** 2).sum(-1), axis=1)
    found = linear.locate(queries, nearest)
    reference = Delaunay(points).find_simplex(queries)
    np.testing.assert_array_equal(found < 0, reference < 0)
    inside = found >= 0
    assert 0.2 < inside.mean() < 0.8
    assert (linear._barycentric(queries[inside], found[inside]) >= -1e-12).all()


def test_a_querys_simplex_does_not_depend_on_its_batch() -> None:
    points = _grid_and_seam_copies()
    linear = Linear(points, points[:, :1])
    rng = np.random.default_rng(5)
    queries = rng.uniform(-0.1, 1.1, (3000, 3))
    queries[:1000, 0] = (rng.integers(0, 10, 1000) + 0.5) / 10  # on the grid's planes
    nearest = np.argmin(((queries[:, None, :] - points[None]) ** 2).sum(-1), axis=1)
    found = linear.locate(queries, nearest)
    order = rng.permutation(len(queries))
    np.testing.assert_array_equal(linear.locate(queries[order], nearest[order]), found[order])
    np.testing.assert_array_equal(linear.locate(queries[:7], nearest[:7]), found[:7])


@pytest.mark.parametrize("d", [2, 3, 4])
def test_outside_marks_only_queries_the_search_finds_in_no_simplex(d: int) -> None:
    rng = np.random.default_rng(30 + d)
    points = rng.random((150, d))
    linear = Linear(points, points[:, :1])
    # Around the hull: just inside, on and just beyond its facets, and far beyond.
    corners = points[linear.tri.convex_hull[rng.integers(0, len(linear.tri.convex_hull), 600)]]
    on_facets = np.einsum("mv,mvj->mj", rng.dirichlet(np.ones(d), 600), corners)
    centre = points.mean(axis=0)
    queries = centre + (on_facets - centre) * rng.choice([1 - 1e-9, 1.0, 1 + 1e-9, 1.5], (600, 1))
    outside = linear.outside(queries)
    assert 0.2 < outside.mean() < 0.3  # the far ones
    assert (linear.search(queries[outside]) < 0).all()


def test_a_walk_starts_from_the_most_regular_simplex_of_each_point() -> None:
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [3.0, 0.0]])
    simplices = np.array([[0, 1, 2], [1, 2, 3], [1, 3, 4]])
    _, regular = transforms_and_regularity(points, simplices)
    np.testing.assert_allclose(regular, [1 / np.sqrt(2), 1.0, 1 / np.sqrt(5)], rtol=1e-15)
    # Point 1 is in all three simplices, 3 in two, 4 in one.
    np.testing.assert_array_equal(most_regular(simplices, regular, 5), [0, 1, 1, 1, 2])
    np.testing.assert_array_equal(most_regular(simplices[:1], regular[:1], 5), [0, 0, 0, -1, -1])


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
