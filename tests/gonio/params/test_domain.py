"""Each closed-form valid domain against brute force.

Brute force: map millions of random direction pairs into the isotropic coordinate box
and record which cells of a grid they reach. A cell whose corners are all valid by
the closed form must be reached; a cell whose corners are all invalid must never be.
"""

import numpy as np
import pytest

import gonio.params as params
from gonio.params.cases import uniform

GRID = 12
HALF = ("rusinkiewicz", "orthographic", "hybrid")


def reached_cells(name: str, n: int = 2_000_000) -> np.ndarray:
    p = params.get(name)
    lo, hi = p.iso_bounds[:, 0], p.iso_bounds[:, 1]
    reached = np.zeros((GRID,) * 3, dtype=bool)
    for seed in range(4):
        c = p.forward_iso(*uniform(n // 4, seed))
        idx = np.clip(((c - lo) / (hi - lo) * GRID).astype(int), 0, GRID - 1)
        reached[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    return reached


def corner_validity(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(all corners valid, no corner valid) per cell, from the closed form."""
    p = params.get(name)
    lo, hi = p.iso_bounds[:, 0], p.iso_bounds[:, 1]
    axes = [np.linspace(lo[j], hi[j], GRID + 1) for j in range(3)]
    corners = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    v = p.valid_iso(corners)
    cells = [
        v[i : i + GRID, j : j + GRID, k : k + GRID] for i in (0, 1) for j in (0, 1) for k in (0, 1)
    ]
    return np.logical_and.reduce(cells), ~np.logical_or.reduce(cells)


@pytest.mark.parametrize("name", HALF)
def test_closed_form_domain_matches_brute_force(name: str) -> None:
    reached = reached_cells(name)
    inside, outside = corner_validity(name)
    assert inside.sum() > 50 and outside.sum() > 50  # the test has teeth on both sides
    assert np.all(reached[inside]), f"{np.sum(~reached[inside])} valid cells never reached"
    assert not np.any(reached[outside]), f"{np.sum(reached[outside])} invalid cells reached"


@pytest.mark.parametrize("name", HALF)
def test_valid_coordinates_come_back_and_invalid_ones_have_no_pair(name: str) -> None:
    """Uniform coordinates: valid ones reproduce themselves through directions; for
    invalid ones the unique candidate pair has a direction below the horizon."""
    p = params.get(name)
    rng = np.random.default_rng(41)
    lo, hi = p.iso_bounds[:, 0], p.iso_bounds[:, 1]
    c = lo + (hi - lo) * rng.random((200_000, 3))
    ok = p.valid_iso(c)
    assert 0.05 < ok.mean() < 0.95
    back = p.forward_iso(*p.inverse_iso(c[ok]))
    rel = np.abs(back - c[ok])
    rel[:, 2] = np.minimum(rel[:, 2], np.pi - rel[:, 2])  # a folded azimuth is modulo π
    far = candidate_min_z(name, c[~ok])
    assert np.all(far < 0.0)
    # Valid coordinates on the reduced box come back, except where the folded azimuth
    # is undefined (‖k‖ = 0) — not hit by uniform samples.
    assert rel.max() < 1e-9


def candidate_min_z(name: str, c: np.ndarray) -> np.ndarray:
    """The smaller z of the unique direction pair with these isotropic coordinates (φh = 0),
    built from the definitions without any clamping and without the closed forms."""
    a, b, rel = c[:, 0], c[:, 1], c[:, 2]
    if name == "hybrid":  # the appendix, θk with its quadrant
        z = 1 - a * a - b * b
        hz = np.sqrt(np.maximum(z, 0))
        cos_a = a * np.cos(rel)
        kz = -b * cos_a / np.sqrt(hz * hz + cos_a * cos_a)
        return np.where(z < 0, z, hz - np.abs(kz))
    if name == "orthographic":  # ω̄ = h̄ ± k̄ as vectors; a direction needs ‖ω̄‖ ≤ 1
        h = np.stack([a, np.zeros_like(a)], 1)
        k = np.stack([b * np.cos(rel), b * np.sin(rel)], 1)
        return 1 - np.maximum(np.sum((h + k) ** 2, 1), np.sum((h - k) ** 2, 1))
    # rusinkiewicz: rotate d̂ and its mirror by explicit matrices rot_y(θh)
    th, td = a, b
    d = np.stack([np.sin(td) * np.cos(rel), np.sin(td) * np.sin(rel), np.cos(td)], 1)
    ry = np.zeros((len(th), 3, 3))
    ry[:, 0, 0], ry[:, 0, 2], ry[:, 1, 1] = np.cos(th), np.sin(th), 1.0
    ry[:, 2, 0], ry[:, 2, 2] = -np.sin(th), np.cos(th)
    wi = np.einsum("nij,nj->ni", ry, d)
    wo = np.einsum("nij,nj->ni", ry, d * [-1, -1, 1])
    return np.minimum(wi[:, 2], wo[:, 2])


def test_spherical_domain_is_the_whole_box() -> None:
    p = params.get("spherical")
    rng = np.random.default_rng(42)
    lo, hi = p.bounds[:, 0], p.bounds[:, 1]
    assert np.all(p.valid(lo + (hi - lo) * rng.random((10_000, 4))))
