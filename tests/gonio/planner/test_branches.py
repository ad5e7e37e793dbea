"""The joint choice of order and inverse-kinematics solutions: the relaxed any-branch
time is the shortest move between usable solutions, every pose returned is a usable
candidate (inside the limits, outside every collision box), the result is the same for
the same inputs, and it is never worse than choosing along a fixed order."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.config import ConfigError
from gonio.planner import build, lkh
from gonio.planner.ordering import order_jointly, order_targets
from gonio.planner.poses import Relaxed, choose
from gonio.planner.schema import PlanSpec
from gonio.planner.search import Metric, path_time
from gonio.rig import constraints
from gonio.rig.model import Rig
from gonio.rig.travel import TravelModel


def random_candidates(
    rng: np.random.Generator, n: int, k: int, tempting: bool
) -> tuple[np.ndarray, np.ndarray]:
    """(candidates (n, k, 4), usable (n, k)), at least one usable per target; with
    ``tempting`` the unusable ones sit at the start pose (0), where every move is free."""
    cand = rng.uniform(-2.0, 2.0, (n, k, 4))
    usable = rng.random((n, k)) < 0.6
    usable[np.arange(n), rng.integers(0, k, n)] = True
    if tempting:
        cand[~usable] = 0.0
    return cand, usable


def brute_relaxed(
    model: TravelModel, cand: np.ndarray, usable: np.ndarray, u: int, v: int
) -> float:
    return min(
        float(model.time(cand[u, a], cand[v, b]))
        for a in range(cand.shape[1])
        for b in range(cand.shape[1])
        if usable[u, a] and usable[v, b]
    )


def test_relaxed_time_is_the_shortest_move_between_usable_solutions(rig: Rig) -> None:
    model = rig.travel
    rng = np.random.default_rng(0)
    cand, usable = random_candidates(rng, 40, 5, tempting=True)
    start = np.zeros(4)
    relaxed = Relaxed.of(model, cand, usable, start)
    u, v = rng.integers(0, 40, 300), rng.integers(0, 40, 300)
    fast = relaxed.times(u, v)
    for i, (a, b) in enumerate(zip(u.tolist(), v.tolist(), strict=True)):
        assert fast[i] == pytest.approx(brute_relaxed(model, cand, usable, a, b), rel=1e-15)
    # The local search's compiled time is the same, bit for bit.
    compiled = Metric.of(model, relaxed.poses, relaxed.usable.sum(axis=1)).times(u, v)
    assert compiled.tobytes() == fast.tobytes()
    # The start is node n, with the start pose only.
    to_start = relaxed.times(np.full(40, 40), np.arange(40))
    expected = [min(model.time(start, cand[i, usable[i]])) for i in range(40)]
    np.testing.assert_allclose(to_start, expected, rtol=1e-15)


def test_relaxed_neighbours_are_the_nearest_in_index_order(rig: Rig) -> None:
    """Each node's neighbours are exactly its nearest others in relaxed time, equal
    times in index order (against every pair)."""
    model = rig.travel
    cand, usable = random_candidates(np.random.default_rng(1), 300, 4, tempting=False)
    cand[7] = cand[3]  # equal times from every node to 3 and 7
    usable[7] = usable[3]
    relaxed = Relaxed.of(model, cand, usable, np.zeros(4))
    nbr, times = relaxed.neighbour_lists(6)
    assert nbr.shape == (301, 6) and np.all(nbr >= 0)
    u, v = np.divmod(np.arange(301 * 301), 301)
    every = relaxed.times(u, v).reshape(301, 301)
    every[np.arange(301), np.arange(301)] = np.inf  # not itself
    best = np.lexsort((np.broadcast_to(np.arange(301), (301, 301)), every), axis=1)[:, :6]
    np.testing.assert_array_equal(nbr, best)
    np.testing.assert_array_equal(times, np.take_along_axis(every, best, axis=1))


@settings(deadline=None, max_examples=15)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 60), k=st.integers(1, 4))
def test_every_pose_returned_is_a_usable_candidate(seed: int, n: int, k: int) -> None:
    """Unusable candidates sit where every move is free; none is ever returned."""
    model = TravelModel(np.full(4, 1.5), np.full(4, 6.0))
    rng = np.random.default_rng(seed)
    cand, usable = random_candidates(rng, n, k, tempting=True)
    nearest = cand[np.arange(n), np.argmax(usable, axis=1)]
    joint = order_jointly(model, cand, usable, nearest, np.zeros(4), kicks=3 * n, seed=seed)
    assert sorted(joint.order.tolist()) == list(range(n))
    for i, target in enumerate(joint.order.tolist()):
        hits = np.all(cand[target] == joint.angles[i], axis=1) & usable[target]
        assert hits.any()
    assert joint.ordering.travel_s == pytest.approx(
        path_time(model, np.zeros(4), joint.angles), rel=1e-12
    )
    np.testing.assert_allclose(joint.travel.sum(), joint.ordering.travel_s, rtol=1e-12)


def spec(isotropic: bool, **fields: object) -> PlanSpec:
    return PlanSpec.model_validate(
        {
            "name": "branches",
            "parametrization": "hybrid",
            "isotropic": isotropic,
            "sampling": {"strategy": "sobol", "target": 200, "seed": 5},
            **fields,
        }
    )


@pytest.mark.parametrize("isotropic", [True, False])
def test_plans_stay_inside_the_limits_and_outside_every_collision_box(
    rigs: dict[str, Rig], isotropic: bool
) -> None:
    for rig in rigs.values():
        plan = build(spec(isotropic, kicks=200), rig)
        lo, hi = rig.limits[:, 0], rig.limits[:, 1]
        assert np.all((plan.angles >= lo) & (plan.angles <= hi))
        for box in rig.spec.constraints.collisions:
            ranges = {
                rig.axes.index(name): (np.radians(a), np.radians(b))
                for name, (a, b) in box.ranges_deg.items()
            }
            assert not constraints.in_box(plan.angles, ranges).any()


def test_the_same_spec_gives_the_same_plan_whatever_the_time_cap(rigs: dict[str, Rig]) -> None:
    rig = rigs["in_plane"]
    a = build(spec(False, kicks=300), rig)
    b = build(spec(False, kicks=300, time_budget_s=1e6), rig)
    assert a.summary.stopped == "converged" == b.summary.stopped
    assert np.array_equal(a.angles, b.angles) and np.array_equal(a.generated, b.generated)
    assert a.summary.travel_s == b.summary.travel_s
    assert a.summary.kicks == b.summary.kicks == 300
    assert a.summary.kicks_kept == b.summary.kicks_kept


def test_joint_choice_beats_choosing_along_the_nearest_home_order(rigs: dict[str, Rig]) -> None:
    """Ordering on the relaxed time, then choosing, is shorter than choosing along the
    order found on the solutions nearest home (the planner before the relaxed time)."""
    rig = rigs["in_plane"]
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(2, 300, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]) + 0.5, np.abs(wo[:, 2]) + 0.5
    wi /= np.linalg.norm(wi, axis=1)[:, None]
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    sol = rig.solve(wi, wo)
    ok = sol.ok
    cand, usable, nearest = sol.candidates[ok], sol.usable[ok], sol.angles[ok]
    joint = order_jointly(rig.travel, cand, usable, nearest, rig.home, kicks=0)
    old = order_targets(rig.travel, nearest, rig.home, kicks=0, lower_bound=False)
    _, along = choose(cand[old.order], usable[old.order], rig.home, rig.travel.time)
    assert joint.ordering.travel_s < 0.99 * along.sum()


def test_small_instances_near_the_any_branch_optimum(rig: Rig) -> None:
    """Five targets with two unrelated solutions each (harder than a rig's mirror
    images): the joint search is within 20 % of the best order with the best choice
    (brute force), and never below it."""
    model = rig.travel
    for seed in range(4):
        cand, usable = random_candidates(np.random.default_rng(seed), 5, 2, tempting=False)
        usable[:] = True
        start = np.zeros(4)
        best = min(
            float(choose(cand[list(p)], usable[list(p)], start, model.time)[1].sum())
            for p in itertools.permutations(range(5))
        )
        joint = order_jointly(model, cand, usable, cand[:, 0], start, kicks=50)
        assert best - 1e-9 <= joint.ordering.travel_s <= 1.2 * best


def test_lkh_ordering_is_kept_only_where_shorter(rigs: dict[str, Rig]) -> None:
    pytest.importorskip("elkai")
    rig = rigs["in_plane"]
    small = {"sampling": {"strategy": "sobol", "target": 120, "seed": 5}, "kicks": 100}
    search_plan = build(spec(False, **small), rig)
    lkh_plan = build(spec(False, ordering="lkh", **small), rig)
    assert lkh_plan.summary.travel_s <= search_plan.summary.travel_s
    assert sorted(lkh_plan.generated.tolist()) == sorted(search_plan.generated.tolist())
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    assert np.all((lkh_plan.angles >= lo) & (lkh_plan.angles <= hi))


def test_lkh_without_elkai_is_one_line(
    rigs: dict[str, Rig], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(lkh, "available", lambda: False)
    with pytest.raises(ConfigError, match=r"^here: ordering: lkh needs elkai: pip install"):
        build(spec(True, ordering="lkh", kicks=0), rigs["arch"], where="here")
