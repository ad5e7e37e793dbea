"""The adaptive density: seeded and deterministic, points distributed as
the density says, the indicator where the BRDF bends, the test measure's density, and
points moved onto the edge of the rig's cap."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gonio import brdf, params
from gonio.planner import adaptive
from gonio.rig.model import Rig

ARCH = Path(__file__).resolve().parents[3] / "configs" / "rigs" / "arch.yaml"


@pytest.fixture(scope="module")
def rig() -> Rig:
    return Rig.from_yaml(ARCH)


@pytest.fixture(autouse=True)
def fewer_measure_pairs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The test measure estimated from 2¹⁵ pairs (a second less per density)."""
    monkeypatch.setattr(adaptive, "MEASURE_PAIRS", 1 << 15)


def peaked() -> adaptive.Density:
    """90 % of the mass in one cell of a 4 × 4 × 4 grid, the rest spread evenly."""
    p = np.full(64, 0.1 / 63)
    p[21] = 0.9
    return adaptive.Density((4, 4, 4), p)


@given(seed=st.integers(0, 2**32 - 1))
def test_a_stream_is_seeded_and_follows_the_density(seed: int) -> None:
    a = adaptive.Stream(peaked(), seed).draw(1024)
    b = adaptive.Stream(peaked(), seed).draw(1024)
    assert a.tobytes() == b.tobytes()
    assert np.all((a >= 0) & (a < 1))
    cell = np.ravel_multi_index(tuple(np.floor(a * 4).astype(int).T), (4, 4, 4))
    counts = np.bincount(cell, minlength=64)
    # The first Sobol coordinate picks the cell: its stratification puts the counts
    # within a point or two of 1024·p.
    assert abs(counts[21] - 0.9 * 1024) <= 2
    assert np.all(np.abs(np.delete(counts, 21) - 0.1 / 63 * 1024) <= 2)


def test_other_seeds_draw_other_points() -> None:
    assert not np.array_equal(
        adaptive.Stream(peaked(), 1).draw(64), adaptive.Stream(peaked(), 2).draw(64)
    )


def test_the_indicator_is_zero_where_the_brdf_is_flat_and_peaks_at_the_lobe() -> None:
    shape = (16, 16, 16)
    lambert = brdf.create("lambert", albedo=0.5)
    assert np.allclose(adaptive.error_indicator(lambert.eval, "rusinkiewicz", True, shape), 0)
    glossy = brdf.create("cook_torrance", alpha=0.1, distribution="ggx", f0=0.04, kd=0.2)
    e = adaptive.error_indicator(glossy.eval, "rusinkiewicz", True, shape).reshape(shape)
    # Rusinkiewicz's first coordinate is θh: the lobe is at θh = 0.
    by_theta_h = e.mean(axis=(1, 2))
    assert by_theta_h[:2].mean() > 20 * by_theta_h[8:].mean()


def test_the_density_puts_most_samples_near_the_specular_peak(rig: Rig) -> None:
    glossy = brdf.create("cook_torrance", alpha=0.1, distribution="ggx", f0=0.04, kd=0.2)
    d = adaptive.density(glossy.eval, rig, "rusinkiewicz", True, floor=0.2)
    assert d.p.sum() == pytest.approx(1.0) and np.all(d.p >= 0)
    points = adaptive.Stream(d, 0).draw(4096)
    theta_h = points[:, 0] * math.pi / 2
    near = np.mean(theta_h < math.radians(10))
    assert near > 0.3  # 10° of θh's 90°: a uniform plan puts about a ninth there


def test_the_test_measure_sums_to_one_and_misses_what_the_rig_cannot_reach(rig: Rig) -> None:
    w = adaptive.measure_density(rig, "rusinkiewicz", True, (32, 32, 32))
    assert w.sum() == pytest.approx(1.0)
    box = adaptive.centres((32, 32, 32))
    # θd near 90° needs a direction below θmax = 80° on both sides: unreachable cells.
    assert np.all(w.reshape(32, 32, 32)[:, -1, :] == 0)
    assert np.count_nonzero(w) > 0.3 * len(box)


@pytest.mark.parametrize("parametrization", params.names())
def test_points_moved_onto_the_edge_of_the_cap(rig: Rig, parametrization: str) -> None:
    p = params.get(parametrization)
    bounds = np.asarray(p.iso_bounds)
    rng = np.random.default_rng(5)
    coords = bounds[:, 0] + rng.random((500, 3)) * (bounds[:, 1] - bounds[:, 0])
    moved, ok = adaptive.onto_edge(coords, rig, parametrization, True)
    assert ok.sum() > 100
    wi, wo = p.inverse_iso(moved[ok])
    top = np.degrees(np.arccos(np.minimum(wi[:, 2], wo[:, 2])))
    off = np.abs(top - math.degrees(rig.theta_max - adaptive.EDGE_MARGIN))
    # Exactly on the edge but for the rare pair whose coordinates' round trip moves it
    # (near a pole of the reduction): still within 0.1°.
    assert np.mean(off < 1e-9) > 0.99 and np.all(off < 0.1)
    assert np.array_equal(moved[~ok], coords[~ok])
