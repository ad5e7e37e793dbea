"""Ordering motor targets: a short open path from the start pose through every target,
with each target's inverse-kinematics solution chosen along the way.

The cost of a move is the rig's travel time (`gonio.rig.travel.TravelModel`, a metric on
joint space). The path starts at the given pose and ends anywhere.

- Construction: the given order (a serpentine over a grid) or nearest neighbour
  (`gonio.planner.nearest`, exact).
- Neighbour lists: each node's `NEIGHBOURS` nearest others by travel time, exactly,
  equal times in index order (`gonio.planner.nearest.nearest_others`).
- Improvement (`gonio.planner.search`): a 2-opt/Or-opt descent over neighbour lists,
  then iterated local search (seeded double-bridge kicks, each kept only if the path got
  shorter). Budgets are counts (improving moves of the descent, `default_moves`; kicks,
  `default_kicks`), so a plan is the same on any machine, however busy; a wall-clock cap
  stays as a safety net, read between slices of counted work, and when it binds the
  result says so. The loops are compiled (`gonio.planner.jit`), before any clock starts
  (`compile_kernels`).
- Branches (`order_jointly`): the order is first improved on the relaxed any-branch time
  (`gonio.planner.poses.Relaxed`: between two targets, the shortest move between any of
  their usable solutions), then the exact choice of solutions along it (Viterbi,
  `gonio.planner.poses.choose`), then improved on those poses and chosen again, while
  that shortens the path.
- Lower bounds: `gonio.planner.bounds` (MST and Held–Karp).
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from gonio import progress
from gonio.planner import search
from gonio.planner.bounds import MAX_PAIRS, mst_bound
from gonio.planner.moves import EPSILON
from gonio.planner.nearest import nearest_neighbour, nearest_others
from gonio.planner.ordered import Ordering, Stop
from gonio.planner.poses import Relaxed, choose
from gonio.planner.search import Metric, Path, path_time
from gonio.rig import TravelModel
from gonio.types import BoolArray, FloatArray

__all__ = [
    "EPSILON",
    "MAX_PAIRS",
    "Joint",
    "Ordering",
    "Stop",
    "compile_kernels",
    "default_kicks",
    "default_moves",
    "mst_lower_bound",
    "nearest_neighbour",
    "neighbour_lists",
    "order_jointly",
    "order_targets",
    "path_time",
]

Method = Literal["given", "nearest", "auto"]

#: Neighbours per node the local search considers.
NEIGHBOURS = 10
#: The default budget of improving moves of the descents: this many per target, plus
#: `MOVES_EXTRA`. The shipped plans' descents converge after at most 1.5 moves per
#: target, a random given order of uniform poses after at most 3, so it binds only on
#: something unusual.
MOVES_PER_TARGET = 10
MOVES_EXTRA = 100
#: The default budget of kicks of the iterated local search: 3 per 2 targets, at most
#: `MAX_KICKS` (a kick and its repair take 0.1–0.3 ms compiled, the longer on the longer
#: paths: benchmarks/planner.py, the trade measured).
KICKS_PER_TWO_TARGETS = 3
MAX_KICKS = 15_000
#: Rounds of "improve on the chosen poses, choose again" after the relaxed order; the
#: first `KICK_ROUNDS` share the kicks the relaxed phase leaves (`RELAXED_SHARE`).
ROUNDS = 4
KICK_ROUNDS = 2
RELAXED_SHARE = 1 / 3

mst_lower_bound = mst_bound  # the name before the bounds had their own module


def default_moves(n: int) -> int:
    """The budget of improving moves (descents) for ``n`` targets when none is given."""
    return MOVES_PER_TARGET * n + MOVES_EXTRA


def default_kicks(n: int) -> int:
    """The budget of kicks (iterated local search) for ``n`` targets when none is given."""
    return min(KICKS_PER_TWO_TARGETS * n // 2, MAX_KICKS)


def neighbour_lists(model: TravelModel, points: FloatArray, k: int) -> np.ndarray:
    """(N, k') indices of each point's k' = min(k, N − 1) nearest others by travel time,
    nearest first, equal times in index order (exact: `gonio.planner.nearest`)."""
    return nearest_others(model, points, np.arange(len(points)), k)[0]


@functools.cache
def compile_kernels() -> None:
    """Compile the search's kernels (`gonio.planner.jit`; on the first run after an
    install, some seconds; later, loaded from the disk) by ordering a toy path, so that
    no clock of a search counts it."""
    with progress.stage("compiling the search (first run only)", None, unit="step"):
        model = TravelModel(np.ones(2), np.ones(2))
        toy = np.array([[0.0, 0.0], [3.0, 0.0], [1.0, 0.0], [2.0, 1.0], [0.0, 2.0]])
        candidates = np.stack([toy, -toy], axis=1)
        usable = np.ones((len(toy), 2), dtype=np.bool_)
        _order_jointly(model, candidates, usable, toy, np.zeros(2), kicks=8)


def _fixed_neighbours(model: TravelModel, points: FloatArray) -> search.Neighbours:
    return search.Neighbours.of(*nearest_others(model, points, np.arange(len(points)), NEIGHBOURS))


def _relaxed_neighbours(relaxed: Relaxed) -> search.Neighbours:
    return search.Neighbours.of(*relaxed.neighbour_lists(NEIGHBOURS))


@dataclass(frozen=True)
class _Effort:
    """What one improvement spent and why it ended."""

    moves: int = 0
    kicks: int = 0
    kept: int = 0
    stopped: Stop = "converged"

    def __add__(self, other: _Effort) -> _Effort:
        both = (self.stopped, other.stopped)
        worst: Stop = next(s for s in ("time cap", "move budget", "converged") if s in both)
        return _Effort(
            self.moves + other.moves, self.kicks + other.kicks, self.kept + other.kept, worst
        )


def _improve(
    path: Path,
    neighbours: search.Neighbours,
    max_moves: int,
    kicks: int,
    rng: np.random.Generator,
    deadline: float,
) -> _Effort:
    """A descent from every target, then ``kicks`` kicks (none if the descent did not
    converge)."""
    with progress.stage("improving the order", None, unit="visit") as shown:
        moves, _, stopped = search.descend(path, neighbours, max_moves, deadline, shown)
        if stopped != "converged" or kicks <= 0:
            return _Effort(moves, 0, 0, stopped)
        tried, kept, _, ended = search.iterate(path, neighbours, kicks, rng, deadline, shown)
    return _Effort(moves, tried, kept, "time cap" if ended == "time cap" else "converged")


def _construct(
    model: TravelModel, targets: FloatArray, start: FloatArray, method: Method, given_s: float
) -> np.ndarray:
    order = np.arange(len(targets))
    if method in ("nearest", "auto"):
        greedy = nearest_neighbour(model, targets, start)
        if method == "nearest" or path_time(model, start, targets[greedy]) < given_s:
            order = greedy
    return order


def order_targets(
    model: TravelModel,
    targets: FloatArray,
    start: FloatArray,
    *,
    method: Method = "auto",
    max_moves: int | None = None,
    kicks: int | None = None,
    seed: int = 0,
    time_budget_s: float = 120.0,
    lower_bound: bool = True,
) -> Ordering:
    """Order ``targets`` (N, A) joint angles (rad) for the shortest travel from ``start``.

    ``method``: "given" improves the order given (e.g. a serpentine), "nearest" starts
    from nearest neighbour, "auto" starts from whichever of the two is shorter. The
    descent stops when no move improves or after ``max_moves`` improving moves (default
    `default_moves`); then ``kicks`` kicks (default `default_kicks`) drawn with
    ``seed``. ``time_budget_s`` of wall time from the call is a safety cap (the
    construction, O(n log n), always runs to the end). Unless the cap binds
    (``stopped == "time cap"``) the result depends only on the inputs. With
    ``lower_bound`` the MST bound over the start and the targets is computed too.
    """
    targets = np.asarray(targets, dtype=np.float64)
    start = np.asarray(start, dtype=np.float64)
    n = len(targets)
    budget = default_moves(n) if max_moves is None else max_moves
    kick_budget = default_kicks(n) if kicks is None else kicks
    compile_kernels()  # before the clock starts: the first run compiles for a while
    started = time.perf_counter()
    deadline = started + time_budget_s
    given_s = path_time(model, start, targets)
    if n == 0:
        return Ordering(np.zeros(0, np.int64), 0.0, 0.0, 0.0, 0.0, True, 0, True, max_moves=budget)
    order = _construct(model, targets, start, method, given_s)
    constructed_s = path_time(model, start, targets[order])
    everything = np.vstack([targets, start[None, :]])  # node n is the start
    neighbours = _fixed_neighbours(model, everything)
    path = Path(order, Metric.of(model, everything))
    rng = np.random.default_rng(seed)
    effort = _improve(path, neighbours, budget, kick_budget, rng, deadline)
    order = path.order()
    travel_s = path_time(model, start, targets[order])
    ordered = time.perf_counter()
    bound, exact = mst_bound(model, everything) if lower_bound else (0.0, False)
    return Ordering(
        order, travel_s, constructed_s, given_s, bound, exact, effort.moves,
        effort.stopped == "converged", stopped=effort.stopped, max_moves=budget,
        order_wall_s=ordered - started, bound_wall_s=time.perf_counter() - ordered,
        kicks=effort.kicks, kicks_kept=effort.kept, max_kicks=kick_budget,
    )  # fmt: skip


@dataclass(frozen=True)
class Joint:
    """An order with one solution per target. ``order`` indexes the targets; ``angles``
    (N, A) and ``travel`` (N,) (the move into each, s) follow it."""

    order: np.ndarray
    angles: FloatArray
    travel: FloatArray
    ordering: Ordering  # the figures of the search (its order is ``order``)
    relaxed_s: float  # the order's length in the relaxed any-branch time (≤ travel)
    rounds: int  # rounds of improving on the chosen poses and choosing again


def order_jointly(
    model: TravelModel,
    candidates: FloatArray,
    usable: BoolArray,
    nearest: FloatArray,
    start: FloatArray,
    *,
    method: Method = "auto",
    max_moves: int | None = None,
    kicks: int | None = None,
    seed: int = 0,
    time_budget_s: float = 120.0,
) -> Joint:
    """Order targets and choose their solutions together.

    ``candidates`` (N, K, A) with ``usable`` (N, K) (at least one per target);
    ``nearest`` (N, A) each target's solution nearest ``start``, on which the order is
    constructed (``method`` as in `order_targets`). Where some target has a choice,
    `RELAXED_SHARE` of the kicks go to the relaxed any-branch time; then solutions are
    chosen along the order (Viterbi), the order is improved on them with the rest, and
    chosen again; further rounds (descents only, at most `ROUNDS` in all) while the path
    shortens. Returned poses are always usable candidates.
    """
    compile_kernels()
    return _order_jointly(
        model,
        candidates,
        usable,
        nearest,
        start,
        method=method,
        max_moves=max_moves,
        kicks=kicks,
        seed=seed,
        time_budget_s=time_budget_s,
    )


def _order_jointly(
    model: TravelModel,
    candidates: FloatArray,
    usable: BoolArray,
    nearest: FloatArray,
    start: FloatArray,
    *,
    method: Method = "auto",
    max_moves: int | None = None,
    kicks: int | None = None,
    seed: int = 0,
    time_budget_s: float = 120.0,
) -> Joint:
    nearest = np.asarray(nearest, dtype=np.float64)
    start = np.asarray(start, dtype=np.float64)
    n = len(nearest)
    budget = default_moves(n) if max_moves is None else max_moves
    kick_budget = default_kicks(n) if kicks is None else kicks
    started = time.perf_counter()
    deadline = started + time_budget_s
    given_s = path_time(model, start, nearest)
    if n == 0:
        empty = Ordering(np.zeros(0, np.int64), 0.0, 0.0, 0.0, 0.0, True, 0, True)
        return Joint(np.zeros(0, np.int64), nearest, np.zeros(0), empty, 0.0, 0)
    order = _construct(model, nearest, start, method, given_s)
    constructed_s = path_time(model, start, nearest[order])
    rng = np.random.default_rng(seed)
    relaxed = Relaxed.of(model, candidates, usable, start)
    effort = _Effort()
    choice = bool((relaxed.usable.sum(axis=1) > 1).any())
    if choice:
        neighbours = _relaxed_neighbours(relaxed)
        path = Path(order, Metric.of(model, relaxed.poses, relaxed.usable.sum(axis=1)))
        share = int(kick_budget * RELAXED_SHARE)
        effort = _improve(path, neighbours, budget, share, rng, deadline)
        order = path.order()
    relaxed_s = float(relaxed.times(np.concatenate([[n], order[:-1]]), order).sum())
    angles, travel = choose(candidates[order], usable[order], start, model.time)
    rounds = 0
    while rounds < ROUNDS and effort.stopped == "converged":
        rounds += 1
        before = float(travel.sum())
        everything = np.vstack([angles, start[None, :]])
        neighbours = _fixed_neighbours(model, everything)
        path = Path(np.arange(n), Metric.of(model, everything))
        left = 0
        if rounds <= KICK_ROUNDS:  # the rest of the kicks, shared
            left = (kick_budget - effort.kicks) // (KICK_ROUNDS - rounds + 1)
        effort += _improve(path, neighbours, budget - effort.moves, left, rng, deadline)
        again = path.order()
        order = order[again]
        angles, travel = choose(candidates[order], usable[order], start, model.time)
        if rounds >= KICK_ROUNDS and not float(travel.sum()) < before - EPSILON:
            break
    travel_s = float(travel.sum())
    ordering = Ordering(
        order, travel_s, constructed_s, given_s, 0.0, False, effort.moves,
        effort.stopped == "converged", stopped=effort.stopped, max_moves=budget,
        order_wall_s=time.perf_counter() - started, kicks=effort.kicks,
        kicks_kept=effort.kept, max_kicks=kick_budget,
    )  # fmt: skip
    return Joint(order, angles, travel, ordering, relaxed_s, rounds)
