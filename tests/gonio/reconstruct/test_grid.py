"""Grid plans: the grid is recognized through read-back scatter, scattered samples are
not a grid, and the grid interpolant is exact at its nodes and across its seams."""

from __future__ import annotations

import numpy as np
import pytest

from gonio import params
from gonio.analysis.measured import Measured
from gonio.brdf.base import BRDF
from gonio.errors import GonioError
from gonio.reconstruct.build import reconstruct
from gonio.reconstruct.coordinates import Space
from gonio.reconstruct.grid import detect
from gonio.rig.model import Rig
from studies.reconstruct.synthetic import synthesize


@pytest.fixture(scope="module")
def grid_iso(arch: Rig, matte: BRDF) -> Measured:
    return synthesize(matte.eval, arch, "hybrid", True, 0, grid=10)


def test_a_grid_plan_is_recognized_through_read_back_scatter(grid_iso: Measured) -> None:
    x = Space("hybrid", True).scaled(grid_iso.wi, grid_iso.wo)
    scattered = x + 1e-4 * np.random.default_rng(0).standard_normal(x.shape)
    grid = detect(scattered)
    assert grid is not None
    centres = (np.arange(10) + 0.5) / 10  # the kept cells' centres (some rows unreachable)
    for nodes in grid.axes:
        assert len(nodes) >= 8
        assert np.abs(nodes[:, None] - centres).min(axis=1).max() < 1e-4


def test_scattered_samples_are_not_a_grid(matte_iso: Measured) -> None:
    assert detect(Space("hybrid", True).scaled(matte_iso.wi, matte_iso.wo)) is None
    with pytest.raises(GonioError, match="do not lie on a grid") as err:
        reconstruct(matte_iso, method="grid")
    assert "\n" not in str(err.value)


def test_a_grid_in_another_parametrization_is_refused(grid_iso: Measured) -> None:
    with pytest.raises(GonioError, match="grid"):
        reconstruct(grid_iso, method="grid", parametrization="spherical")


def test_the_grid_reconstruction_is_exact_at_its_nodes(grid_iso: Measured) -> None:
    r = reconstruct(grid_iso, method="grid")
    f, _, ok = r.evaluate(grid_iso.wi, grid_iso.wo)
    # Nodes whose every neighbouring cell misses a corner are not supported.
    assert ok.mean() > 0.5
    np.testing.assert_allclose(f[ok], grid_iso.f[ok], rtol=1e-12)


def test_values_either_side_of_the_grids_seam_agree(grid_iso: Measured) -> None:
    r = reconstruct(grid_iso, method="grid")
    p = params.get("hybrid")
    coords = np.random.default_rng(5).uniform(0.1, 0.5, (400, 3))
    sides = []
    for phi in (1e-9, np.pi - 1e-9):
        c = coords.copy()
        c[:, 2] = phi
        sides.append(c)
    keep = p.valid_iso(sides[0]) & p.valid_iso(sides[1])
    (a, oka), (b, okb) = (
        (r.eval(*p.inverse_iso(c[keep])), r.supported(*p.inverse_iso(c[keep]))) for c in sides
    )
    both = oka & okb
    assert both.sum() > 50
    np.testing.assert_allclose(a[both], b[both], rtol=1e-6)
