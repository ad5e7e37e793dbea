"""`SimMotorBus`: the MotorBus protocol on a virtual clock — trapezoidal motion timed
as the planner predicts, limits refused before anything moves, timeouts that hold,
and the position effects (ticks, backlash, repeatability) with their statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.errors import DriverError, LimitError, MotionTimeout
from gonio.rig.model import Rig
from gonio.scene import PositionErrorSpec
from sim.clock import ManualClock
from sim.virtual.devices.motors import SimMotorBus, profile_position
from sim.virtual.physics.streams import Streams
from tests.support.rigs import angle_between


def bus(
    rig: Rig, clock: ManualClock | None = None, spec: PositionErrorSpec | None = None, seed: int = 0
) -> SimMotorBus:
    return SimMotorBus(rig, clock or ManualClock(), position_error=spec, streams=Streams(seed))


def pose(rig: Rig, values: list[float]) -> dict[str, float]:
    return dict(zip(rig.axes, values, strict=True))


TARGET = [0.6, -1.0, 0.8, 1.5]


def test_a_move_takes_the_planned_travel_time(rig: Rig) -> None:
    """`wait_settled` ends when the motion ends; the settle dwell is the caller's."""
    clock = ManualClock()
    with bus(rig, clock) as b:
        b.move_to(pose(rig, TARGET))
        b.wait_settled(60.0)
        expected = float(rig.travel_time(rig.home, np.array(TARGET)))
        assert clock.now() == pytest.approx(expected, rel=1e-12)
        assert list(b.positions().values()) == TARGET
        assert b.true_positions() == b.positions()
        assert set(b.health()) == set(rig.axes)


def test_positions_follow_the_trapezoid_mid_move(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    with bus(rig, clock) as b:
        b.move_to(pose(rig, TARGET))
        total = float(rig.travel_time(rig.home, np.array(TARGET)))
        per_axis = rig.travel.time(rig.home[None, :] * 0, np.diag(np.abs(TARGET)))
        slowest = int(np.argmax(per_axis))
        clock.advance(total / 2)
        here = np.array(list(b.positions().values()))
        # The slowest axis is exactly halfway (the profile is symmetric) ...
        assert here[slowest] == pytest.approx(TARGET[slowest] / 2, rel=1e-12)
        # ... and every axis is between its start and its goal.
        assert np.all(np.abs(here) <= np.abs(TARGET) + 1e-15)
        assert np.all(np.sign(here) == np.sign(TARGET))


@pytest.mark.parametrize(
    ("d", "v", "a"), [(0.1, 1.0, 1.0), (3.0, 1.0, 2.0), (1.0, 1.0, 1.0), (1e-9, 0.5, 4.0)]
)
def test_profile_is_continuous_and_ends_on_the_goal(d: float, v: float, a: float) -> None:
    start, goal = np.array([0.0]), np.array([d])
    vv, aa = np.array([v]), np.array([a])
    t_end = 2 * math.sqrt(d / a) if d < v * v / a else d / v + v / a
    t = np.linspace(0.0, t_end, 2001)
    x = np.array([profile_position(start, goal, vv, aa, float(s))[0] for s in t])
    assert x[0] == 0.0
    assert x[-1] == pytest.approx(d, rel=1e-12)
    speed = np.diff(x) / np.diff(t)
    assert np.all(speed >= -1e-12) and speed.max() <= v * (1 + 1e-9)
    assert profile_position(start, goal, vv, aa, t_end + 1.0)[0] == d


def test_limits_are_refused_before_anything_moves(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    with bus(rig, clock) as b:
        before = b.positions()
        for bad in (math.radians(86.0), math.nan, math.inf):
            with pytest.raises(LimitError, match="light_elevation"):
                b.move_to({"light_elevation": bad, "detector_azimuth": 0.5})
        assert b.positions() == before
        b.wait_settled(1.0)
        assert b.positions() == before  # the valid axis in the refused command did not move
        with pytest.raises(DriverError, match="unknown axis 'elbow'"):
            b.move_to({"elbow": 0.1})


def test_timeout_holds_where_the_axes_are(rigs: dict[str, Rig]) -> None:
    rig = rigs["in_plane"]
    clock = ManualClock()
    with bus(rig, clock) as b:
        b.move_to(pose(rig, [1.5, -1.5, 1.0, 3.0]))
        with pytest.raises(MotionTimeout, match=r"did not settle within 0\.5 s"):
            b.wait_settled(0.5)
        assert clock.now() == 0.5
        held = b.positions()
        clock.advance(10.0)
        assert b.positions() == held
        assert 0 < held["light_arm"] < 1.5


def test_stop_torque_and_closed_bus(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    b = bus(rig, clock)
    with pytest.raises(DriverError, match="not open"):
        b.move_to(pose(rig, TARGET))
    with b:
        b.move_to(pose(rig, TARGET))
        clock.advance(0.3)
        b.stop()
        held = b.positions()
        clock.advance(5.0)
        assert b.positions() == held
        b.torque(False)
        with pytest.raises(DriverError, match="torque is off"):
            b.move_to(pose(rig, TARGET))
        b.torque(True)
        b.move_to(pose(rig, TARGET))
    # Leaving the context stops the motion; a closed bus answers nothing.
    with pytest.raises(DriverError, match="not open"):
        b.positions()
    with b:
        end = b.positions()
        clock.advance(30.0)
        assert b.positions() == end


def test_tick_quantization_bounds_the_direction_error(rig: Rig) -> None:
    """The encoder reads the tick the motor went to; the joint is there too, so the
    measured pair differs from the commanded one by at most the half-ticks of the
    axes in each chain."""
    rng = np.random.default_rng(0)
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    ticks = np.array([a.resolution_rad for a in rig.bus_axes()])
    worst_i = worst_o = 0.0
    with bus(rig, spec=PositionErrorSpec(ticks=True)) as b:
        for _ in range(200):
            target = rng.uniform(lo, hi)
            b.move_to(pose(rig, target.tolist()))
            b.wait_settled(600.0)
            read = np.array(list(b.positions().values()))
            assert np.all(np.abs(read - target) <= ticks / 2 * (1 + 1e-9))
            steps = (read - np.array([a.zero_offset_rad for a in rig.bus_axes()])) / ticks
            assert np.allclose(steps, np.round(steps), atol=1e-6)
            assert list(b.true_positions().values()) == read.tolist()
            wi, wo = rig.forward(read)
            ci, co = rig.forward(target)
            worst_i = max(worst_i, float(angle_between(wi, ci)))
            worst_o = max(worst_o, float(angle_between(wo, co)))
    chains = {c: getattr(rig.spec, c).axes for c in ("light", "detector", "sample")}
    half = {n: t / 2 for n, t in zip(rig.axes, ticks, strict=True)}
    bound_i = sum(half[n] for n in (*chains["light"], *chains["sample"]))
    bound_o = sum(half[n] for n in (*chains["detector"], *chains["sample"]))
    assert 0 < worst_i <= bound_i * (1 + 1e-9)
    assert 0 < worst_o <= bound_o * (1 + 1e-9)


def test_backlash_depends_on_the_approach_direction(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    spec = PositionErrorSpec(ticks=False, backlash_deg=0.2)
    with bus(rig, spec=spec) as b:
        b.move_to(pose(rig, [0.5, 0.2, 0.3, 0.1]))  # from home: every axis moves up
        b.wait_settled(60.0)
        from_below = np.array(list(b.true_positions().values()))
        b.move_to(pose(rig, [1.0, 0.6, 0.9, 0.7]))
        b.wait_settled(60.0)
        b.move_to(pose(rig, [0.5, 0.2, 0.3, 0.1]))  # the same goals, approached from above
        b.wait_settled(60.0)
        from_above = np.array(list(b.true_positions().values()))
        assert list(b.positions().values()) == [0.5, 0.2, 0.3, 0.1]
    np.testing.assert_allclose(from_above - from_below, math.radians(0.2), rtol=1e-9)
    np.testing.assert_allclose(from_below - [0.5, 0.2, 0.3, 0.1], -math.radians(0.1), rtol=1e-9)


def test_repeatability_statistics_and_per_sample_reproducibility(rigs: dict[str, Rig]) -> None:
    rig = rigs["in_plane"]
    sigma = math.radians(0.05)
    spec = PositionErrorSpec(ticks=False, repeatability_deg=0.05)
    errors = []
    with bus(rig, spec=spec, seed=11) as b:
        for i in range(2000):
            b.begin_sample(i)
            sign = (-1) ** i
            b.move_to(pose(rig, [0.2 * sign, 0.3 * sign, 0.1 * sign, 0.4 * sign]))
            b.wait_settled(60.0)
            errors.append(
                np.array(list(b.true_positions().values())) - list(b.positions().values())
            )
    e = np.array(errors)
    assert np.allclose(e.mean(axis=0), 0.0, atol=4 * sigma / math.sqrt(2000))
    np.testing.assert_allclose(e.std(axis=0), sigma, rtol=0.06)
    # Sample 1234 alone, on a fresh bus, moves to the same error.
    with bus(rig, spec=spec, seed=11) as b:
        b.begin_sample(1234)
        b.move_to(pose(rig, [0.2, 0.3, 0.1, 0.4]))
        b.wait_settled(60.0)
        alone = np.array(list(b.true_positions().values())) - list(b.positions().values())
    np.testing.assert_array_equal(alone, e[1234])


def test_an_axis_that_stays_put_keeps_its_error(rigs: dict[str, Rig]) -> None:
    """Only the axes that move draw a new repeatability error (and may change backlash
    side); commanding the pose the motors are at changes nothing."""
    rig = rigs["arch"]
    spec = PositionErrorSpec(ticks=False, backlash_deg=0.1, repeatability_deg=0.05)
    with bus(rig, spec=spec, seed=3) as b:
        b.begin_sample(0)
        b.move_to(pose(rig, [0.3, 0.2, 0.4, 0.5]))
        b.wait_settled(60.0)
        first = np.array(list(b.true_positions().values()))
        b.begin_sample(1)
        b.move_to({"light_elevation": 0.6})
        b.wait_settled(60.0)
        second = np.array(list(b.true_positions().values()))
        b.begin_sample(2)
        b.move_to(pose(rig, [0.6, 0.2, 0.4, 0.5]))  # where the motors already are
        b.wait_settled(60.0)
        third = np.array(list(b.true_positions().values()))
    assert second[0] != first[0] + 0.3  # the light moved: a new error
    np.testing.assert_array_equal(second[1:], first[1:])
    np.testing.assert_array_equal(third, second)


def test_waiting_again_after_the_motion_ended_takes_no_time(rigs: dict[str, Rig]) -> None:
    rig = rigs["arch"]
    clock = ManualClock()
    with SimMotorBus(rig, clock) as b:
        b.move_to({"light_elevation": 1.0})
        with pytest.raises(MotionTimeout, match="the move needs"):
            b.wait_settled(1.0)
        assert clock.now() == 1.0
        b.move_to({"light_elevation": 1.02})
        b.wait_settled(10.0)
        settled = clock.now()
        b.wait_settled(10.0)  # already settled: no more time passes
        assert clock.now() == settled
