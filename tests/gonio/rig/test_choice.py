"""Among several inverse-kinematics solutions, `solve` takes the usable one with the
shortest travel time (`TravelModel.time`, the slowest axis's trapezoidal move) from
``previous`` (the home pose by default)."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.rig.model import Rig
from gonio.types import FloatArray
from tests.conftest import RIG_NAMES
from tests.gonio.rig.helpers import column
from tests.support.rigs import direction

#: (rig, wi, wo, number of usable candidates): pairs with several usable solutions. The
#: arch with the light within 5° of the normal has four (light ±θi, detector ±θo); the
#: in-plane rig has two (the plane's normal m or −m), and a third where the sample
#: rotation of one of them is within 20° of ±180°: the ±200° stage reaches it both ways.
SEVERAL = [
    ("arch", direction(3.0, 40.0), direction(40.0, 200.0), 4),
    ("in_plane", direction(30.0, 20.0), direction(50.0, 200.0), 3),
    ("in_plane", direction(45.0, 10.0), direction(30.0, 100.0), 3),
]


def solve_one(rig: Rig, wi: FloatArray, wo: FloatArray, previous: FloatArray | None) -> FloatArray:
    return rig.solve(wi[None], wo[None], previous=previous).angles[0]


@pytest.mark.parametrize(("name", "wi", "wo", "count"), SEVERAL)
def test_previous_pose_decides_between_solutions(
    rigs: dict[str, Rig], name: str, wi: FloatArray, wo: FloatArray, count: int
) -> None:
    rig = rigs[name]
    solution = rig.solve(wi[None], wo[None])
    candidates = solution.candidates[0]
    assert solution.usable[0].sum() == count
    assert len({tuple(np.round(c, 9)) for c in candidates[solution.usable[0]]}) == count
    # Standing on a solution: that one is taken (travel 0), whichever it is.
    for k in np.flatnonzero(solution.usable[0]):
        assert np.array_equal(solve_one(rig, wi, wo, candidates[k]), candidates[k])
    # Near a solution (every axis 2° off): still that one.
    for k in np.flatnonzero(solution.usable[0]):
        near = candidates[k] + np.radians(2.0)
        assert np.array_equal(solve_one(rig, wi, wo, near), candidates[k])


@pytest.mark.parametrize(("name", "wi", "wo", "count"), SEVERAL)
def test_default_start_is_home(
    rigs: dict[str, Rig], name: str, wi: FloatArray, wo: FloatArray, count: int
) -> None:
    rig = rigs[name]
    solution = rig.solve(wi[None], wo[None])
    times = rig.travel.time(rig.home, solution.candidates[0])
    assert np.array_equal(solution.angles[0], solution.candidates[0, np.argmin(times)])
    assert np.array_equal(solve_one(rig, wi, wo, rig.home), solution.angles[0])


@pytest.mark.parametrize("name", RIG_NAMES)
def test_pick_is_the_fastest_usable_move(rigs: dict[str, Rig], name: str) -> None:
    """Random starting poses: the pick is the argmin of the travel time over the usable
    candidates (a brute-force check); the nearest candidate in joint distance is
    sometimes another one, so the time model, not the distance, is what decides."""
    rig = rigs[name]
    rng = np.random.default_rng(5)
    differs = 0
    for name_, wi, wo, _ in SEVERAL:
        if name_ != name:
            continue
        base = rig.solve(wi[None], wo[None])
        usable = base.candidates[0][base.usable[0]]
        for _ in range(200):
            start = rng.uniform(rig.limits[:, 0], rig.limits[:, 1])
            picked = solve_one(rig, wi, wo, start)
            times = rig.travel.time(start, usable)
            assert rig.travel.time(start, picked) == times.min()
            assert any(np.array_equal(picked, c) for c in usable)
            distance = np.linalg.norm(usable - start, axis=1)
            differs += not np.array_equal(usable[np.argmin(distance)], picked)
    assert differs > 0


def test_unusable_solution_is_never_picked(rigs: dict[str, Rig]) -> None:
    """Arch, detector opposite the light: only one of the four solutions is usable (the
    others need the azimuth in the ±179° gap or the light at −30°); even starting on an
    unusable one, the usable one is taken."""
    rig = rigs["arch"]
    wi, wo = direction(30.0, 0.0), direction(40.0, 180.0)
    solution = rig.solve(wi[None], wo[None])
    usable = np.flatnonzero(solution.usable[0])
    assert len(usable) == 1  # of 12: 4 solutions × the rotation stage at ψ − 2π, ψ, ψ + 2π
    only = solution.candidates[0, usable[0]]
    for start in solution.candidates[0]:
        assert np.array_equal(solve_one(rig, wi, wo, start), only)
    assert only[column(rig, "detector_elevation")] < 0.0


def test_batch_shares_one_previous_pose(rigs: dict[str, Rig]) -> None:
    """``previous`` (A,) applies to every pair of a batch: each row picks as alone."""
    rig = rigs["arch"]
    wi = np.stack([p[1] for p in SEVERAL[:1]] * 3)
    wo = np.stack([p[2] for p in SEVERAL[:1]] * 3)
    first = rig.solve(wi[:1], wo[:1])
    for start in first.candidates[0][first.usable[0]]:
        batch = rig.solve(wi, wo, previous=start)
        assert all(np.array_equal(row, start) for row in batch.angles)


def test_an_extended_stage_uses_its_whole_range(rigs: dict[str, Rig]) -> None:
    """The sample rotation (±200°) standing at 190°: a pair that needs ψ = 190° ≡ −170°
    is measured without moving it, not after a 360° turn."""
    rig = rigs["arch"]
    previous = np.radians([20.0, 30.0, 40.0, 190.0])
    wi, wo = rig.forward(previous)
    angles = rig.solve(wi[None], wo[None], previous=previous).angles[0]
    np.testing.assert_allclose(angles, previous, atol=1e-12)
    assert float(rig.travel.time(previous, angles)) < 1e-5
