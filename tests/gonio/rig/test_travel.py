"""`TravelModel`: the trapezoidal move time, its inverse `reach`, the scalar twin used by
the local search, and the metric properties the ordering's lower bound relies on."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel
from tests.conftest import RIG_NAMES


def trapezoid(d: float, v: float, a: float) -> float:
    """The move time from first principles: accelerate at a to the peak speed, then
    brake; the peak is min(v, √(a d))."""
    peak = min(v, math.sqrt(a * d))
    ramp = peak / a  # each of the two ramps
    covered = peak * ramp  # by both ramps together: 2 · ½ a ramp²
    return 2.0 * ramp + (d - covered) / v if peak == v else 2.0 * ramp


def single(v: float, a: float) -> TravelModel:
    return TravelModel(np.array([v]), np.array([a]))


def axis_dynamics(rig: Rig) -> list[tuple[float, float]]:
    """(v rad/s, a rad/s²) of the rig's axes, each distinct pair once."""
    return sorted(
        {(float(v), float(a)) for v, a in zip(rig.velocity, rig.acceleration, strict=True)}
    )


@pytest.mark.parametrize(
    "fraction", [0.0, 1e-9, 0.01, 0.5, 1 - 1e-9, 1.0, 1 + 1e-9, 1.5, 10.0, 100.0]
)
def test_time_is_the_trapezoid(rig: Rig, fraction: float) -> None:
    """At, below and above the knee d = v² / a where cruising starts, on every axis."""
    for v, a in axis_dynamics(rig):
        d = fraction * v * v / a
        expected = pytest.approx(trapezoid(d, v, a), rel=1e-14, abs=0)
        assert single(v, a).time([0.0], [d]) == expected, (v, a)
        assert single(v, a).time([d], [0.0]) == single(v, a).time([0.0], [d])


def test_time_is_continuous_and_smooth_at_the_knee(rig: Rig) -> None:
    for v, a in axis_dynamics(rig):
        continuous_and_smooth_at_the_knee(v, a)


def continuous_and_smooth_at_the_knee(v: float, a: float) -> None:
    model = single(v, a)
    knee = v * v / a
    assert model.time([0.0], [knee]) == pytest.approx(2.0 * v / a, rel=1e-15)
    for eps in (1e-12, 1e-9, 1e-6):
        below = model.time([0.0], [knee * (1 - eps)])
        above = model.time([0.0], [knee * (1 + eps)])
        assert below < model.time([0.0], [knee]) < above
        assert abs(above - below) <= 1.01 * 2 * eps * knee / v + 1e-15
    # The slope is 1 / v on both sides (the time is C¹ across the knee).
    h = 1e-6 * knee
    left = (model.time([0.0], [knee]) - model.time([0.0], [knee - h])) / h
    right = (model.time([0.0], [knee + h]) - model.time([0.0], [knee])) / h
    assert left == pytest.approx(1.0 / v, rel=1e-5)
    assert right == pytest.approx(1.0 / v, rel=1e-5)


@pytest.mark.parametrize("fraction", [1e-6, 0.3, 1 - 1e-9, 1.0, 1 + 1e-9, 2.0, 20.0])
def test_reach_inverts_time_on_each_axis(rig: Rig, fraction: float) -> None:
    model = rig.travel
    knees = model.velocity**2 / model.acceleration
    for j, knee in enumerate(knees):
        d = fraction * knee
        q = np.zeros(len(knees))
        q[j] = d
        t = float(model.time(np.zeros(len(knees)), q))
        assert t == pytest.approx(trapezoid(d, model.velocity[j], model.acceleration[j]), rel=1e-14)
        assert model.reach(t)[j] == pytest.approx(d, rel=1e-12)
        assert np.all(model.reach(t) >= q * (1 - 1e-12))  # the other axes reach farther


def test_time_is_the_slowest_axis_and_broadcasts(rigs: dict[str, Rig]) -> None:
    model = rigs["in_plane"].travel
    rng = np.random.default_rng(0)
    p = rng.uniform(-3, 3, (5, 7, 4))
    q = rng.uniform(-3, 3, (7, 4))
    times = model.time(p, q)
    assert times.shape == (5, 7)
    single_axis = [
        [
            single(v, a).time([x], [y])
            for v, a, x, y in zip(model.velocity, model.acceleration, pp, qq, strict=True)
        ]
        for pp, qq in zip(p.reshape(-1, 4), np.broadcast_to(q, p.shape).reshape(-1, 4), strict=True)
    ]
    assert np.array_equal(times.ravel(), np.max(single_axis, axis=1))
    assert np.all(model.time(p, p) == 0.0)


def test_rejects_nonpositive_dynamics() -> None:
    with pytest.raises(ValueError, match="positive"):
        TravelModel(np.array([1.0, -1.0]), np.array([1.0, 1.0]))
    with pytest.raises(ValueError, match="positive"):
        TravelModel(np.array([1.0]), np.array([0.0]))
    with pytest.raises(ValueError, match="one per axis"):
        TravelModel(np.array([1.0, 1.0]), np.array([1.0]))


def test_scalar_equals_time(rig: Rig) -> None:
    model = rig.travel
    scalar = model.scalar()
    rng = np.random.default_rng(1)
    p = rng.uniform(-4, 4, (2000, 4))
    # Moves in every regime: some axes tiny (below the knee), some long.
    q = p + rng.uniform(-1, 1, (2000, 4)) * 10.0 ** rng.uniform(-6, 0.6, (2000, 4))
    expected = model.time(p, q)
    got = np.array([scalar(list(a), list(b)) for a, b in zip(p, q, strict=True)])
    assert np.abs(got - expected).max() <= 1e-15 * np.maximum(expected, 1.0).max()
    assert scalar(list(p[0]), list(p[0])) == 0.0


poses = st.lists(st.floats(-4.0, 4.0), min_size=4, max_size=4)


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(RIG_NAMES), p=poses, q=poses, r=poses)
def test_triangle_inequality(
    rigs: dict[str, Rig], name: str, p: list[float], q: list[float], r: list[float]
) -> None:
    model = rigs[name].travel
    pq, qr, pr = model.time(p, q), model.time(q, r), model.time(p, r)
    assert pr <= pq + qr + 1e-12
    assert model.time(q, p) == pq  # symmetric
    scalar = model.scalar()
    assert abs(scalar(p, r) - pr) <= 1e-15 * max(1.0, pr)


@settings(max_examples=200, deadline=None)
@given(name=st.sampled_from(RIG_NAMES), p=poses, q=poses, t=st.floats(0.0, 10.0))
def test_reach_bounds_every_axis(
    rigs: dict[str, Rig], name: str, p: list[float], q: list[float], t: float
) -> None:
    """time(p, q) ≤ t exactly when every |q_j − p_j| ≤ reach(t)_j (up to rounding)."""
    model = rigs[name].travel
    move = np.abs(np.subtract(q, p))
    reach = model.reach(t)
    time = float(model.time(p, q))
    if time <= t * (1 - 1e-12):
        assert np.all(move <= reach * (1 + 1e-12))
    if np.all(move <= reach * (1 - 1e-12)):
        assert time <= t * (1 + 1e-12)
