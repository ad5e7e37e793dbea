"""Local search on an open path: 2-opt and Or-opt descent, and iterated local search,
compiled (numba).

The path starts at a fixed node S and ends at a free end E (every move into E costs
nothing), so it is an open path from S. Move times come from a `Metric`: each node's
poses, the time between two nodes the shortest move between any of theirs (one pose a
node: the travel time between fixed poses; several: the relaxed any-branch time,
`gonio.planner.poses.Relaxed`), each axis on its trapezoidal profile
(`gonio.rig.travel.TravelModel`, the same arithmetic, bit for bit).

- `descend`: 2-opt and Or-opt (segments of 1 to 3, either orientation) from each node
  in a queue, over neighbour lists, first improvement, don't-look bits; until no move
  gains more than `EPSILON`, a budget of improving moves is spent, or a deadline passes.
- `iterate`: kicks, each a double bridge within a window of the path (two adjacent
  segments of random lengths ≤ `KICK_SPAN` swapped), followed by a descent from the six
  nodes it touched; kept if the path got shorter by more than `EPSILON`, otherwise
  undone exactly (the positions written since the last kept state restored from a copy).
  Kicks are drawn from a seeded `numpy.random.Generator`, so a seed and a kick budget
  give the same path anywhere.

The search is sequential by nature (each move changes the next one's costs): it runs as
compiled loops over the path's arrays. The work is counted (improving moves, node
visits, kicks), never timed inside: the compiled loops return every `SLICE` node visits
or `KICK_BATCH` kicks, and only there is the deadline read, a safety stop whose
binding is reported ("time cap"). Whatever the machine's load, a result that did not
stop on the deadline is the same.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from gonio.planner.jit import compiled
from gonio.planner.moves import EPSILON, Ints, cost, or_opt, times, two_opt, write
from gonio.planner.ordered import Stop
from gonio.progress import Progress, Quiet
from gonio.rig import TravelModel
from gonio.types import BoolArray, FloatArray

#: The longest segment a kick moves (targets).
KICK_SPAN = 30
#: Node visits of a descent between two readings of the clock.
SLICE = 1 << 14
#: Kicks between two readings of the clock.
KICK_BATCH = 64


def path_time(model: TravelModel, start: FloatArray, targets: FloatArray) -> float:
    """Travel time (s) from ``start`` through ``targets`` (N, A) in the given order."""
    if len(targets) == 0:
        return 0.0
    previous = np.vstack([np.asarray(start, dtype=np.float64)[None, :], targets[:-1]])
    return float(model.time(previous, targets).sum())


@dataclass(frozen=True)
class Metric:
    """Move times between nodes as arrays for compiled code: node u's poses are
    ``poses[u, :count[u]]`` ((M, K, A) rad, ``count`` (M,) ≥ 1), the time between two
    nodes the shortest move between any of their poses; ``axes`` (4, A) each axis's
    velocity, acceleration, v²/a and v/a (`TravelModel.time`'s terms)."""

    poses: FloatArray
    count: np.ndarray
    axes: FloatArray

    @classmethod
    def of(cls, model: TravelModel, poses: FloatArray, count: np.ndarray | None = None) -> Metric:
        """From poses (M, A) (one a node) or (M, K, A) with ``count`` (M,) usable ones
        packed first."""
        p = np.asarray(poses, dtype=np.float64)
        if p.ndim == 2:
            p = p[:, None, :]
        c = np.ones(len(p), np.int64) if count is None else np.asarray(count, np.int64)
        v, a = model.velocity, model.acceleration
        axes = np.ascontiguousarray(np.stack([v, a, v * v / a, v / a]), dtype=np.float64)
        return cls(np.ascontiguousarray(p), np.ascontiguousarray(c), axes)

    def times(self, u: np.ndarray, v: np.ndarray) -> FloatArray:
        """Move times (s) between nodes ``u`` and ``v`` (P,) (the compiled cost)."""
        u = np.ascontiguousarray(u, dtype=np.int64)
        v = np.ascontiguousarray(v, dtype=np.int64)
        return np.asarray(times(self.poses, self.count, self.axes, u, v), dtype=np.float64)


@dataclass(frozen=True)
class Neighbours:
    """Each node's nearest others, nearest first (``nodes`` (M, k), −1 pads a short
    row) with the move time to each (``times`` (M, k) s)."""

    nodes: np.ndarray
    times: FloatArray

    @classmethod
    def of(cls, nodes: np.ndarray, times: FloatArray) -> Neighbours:
        return cls(
            np.ascontiguousarray(nodes, dtype=np.int64),
            np.ascontiguousarray(times, dtype=np.float64),
        )


class Path:
    """An open path: node S (the start, id n) first, node E (id n + 1, a free end) last,
    targets 0..n-1 in between, with the `Metric` of the targets and the start (n + 1
    nodes). ``nodes`` (n + 2,) the path, ``pos`` (n + 2,) each node's position."""

    def __init__(self, order: np.ndarray, metric: Metric):
        n = len(order)
        self.n, self.metric = n, metric
        self.S, self.E = n, n + 1
        self.nodes = np.concatenate([[self.S], order, [self.E]]).astype(np.int64)
        self.pos = np.empty(n + 2, dtype=np.int64)
        self.pos[self.nodes] = np.arange(n + 2)
        #: The first and last positions written since the last kept state ([1, 0]: none).
        self.dirty = np.array([1, 0], dtype=np.int64)

    def order(self) -> np.ndarray:
        """The targets in visiting order (a copy)."""
        return self.nodes[1:-1].copy()

    def length(self) -> float:
        """The path's time (s), summed in order."""
        return float(self.metric.times(self.nodes[:-2], self.nodes[1:-1]).sum())


def descend(
    path: Path,
    neighbours: Neighbours,
    max_moves: int,
    deadline: float,
    shown: Progress | None = None,
) -> tuple[int, float, Stop]:
    """2-opt and Or-opt moves from every target (queued in index order) until none
    improves, ``max_moves`` have been applied or ``deadline`` (`time.perf_counter`) has
    passed (read every `SLICE` node visits). Returns (moves applied, time gained (s), why
    it stopped).

    Deterministic but for the deadline: neighbours are visited nearest first, the first
    improving move found is applied, a move wakes the nodes at its ends. Each node visit
    costs a bounded number of cost evaluations, so ``max_moves`` bounds the work too.
    ``shown`` counts the node visits (`gonio.progress`).
    """
    n = path.n
    queue = np.empty(n + 2, dtype=np.int64)
    queue[:n] = np.arange(n)
    ends = np.array([0, n], dtype=np.int64)  # head, count
    queued = np.zeros(n + 2, dtype=np.bool_)
    queued[:] = True  # every target queued; S and E never enter the queue
    m = path.metric
    show = (Quiet() if shown is None else shown).advance
    moves, gained = 0, 0.0
    while True:  # the clock read before each slice of work, as the budget
        if ends[1] > 0 and moves < max_moves and time.perf_counter() > deadline:
            return moves, gained, "time cap"
        applied, won, visits, status = _descend(
            m.poses, m.count, m.axes, neighbours.nodes, neighbours.times, path.nodes,
            path.pos, path.dirty, queue, ends, queued, min(max_moves - moves, 1 << 62), SLICE,
        )  # fmt: skip
        moves += applied
        gained += won
        show(visits)
        if status == _CONVERGED:
            return moves, gained, "converged"
        if status == _BUDGET:
            return moves, gained, "move budget"


def iterate(
    path: Path,
    neighbours: Neighbours,
    kicks: int,
    rng: np.random.Generator,
    deadline: float,
    shown: Progress | None = None,
) -> tuple[int, int, float, Stop]:
    """Up to ``kicks`` kicks, each followed by a descent from the nodes it touched and
    undone unless the path got shorter. Returns (kicks tried, kicks kept, time gained
    (s), why it stopped: "move budget" when the kicks ran out, or "time cap", the
    deadline read every `KICK_BATCH` kicks).

    A kick swaps two adjacent segments B, C of lengths in 1..`KICK_SPAN` (A B C D →
    A C B D: a double bridge, the move 2-opt and Or-opt cannot undo in one step). The
    descent after a kick may apply any number of moves. The path must have no improving
    move pending (after `descend` converged).
    """
    n = path.n
    if n < 3:
        return 0, 0, 0.0, "converged"
    span = min(KICK_SPAN, max(1, (n - 1) // 2))
    m = path.metric
    queue = np.empty(n + 16, dtype=np.int64)
    queued = np.zeros(n + 2, dtype=np.bool_)
    queued[n:] = True  # S and E never enter the queue
    backup = path.nodes.copy()
    path.dirty[:] = (1, 0)
    show = (Quiet() if shown is None else shown).advance
    kept, gained = 0, 0.0
    for lo in range(0, kicks, KICK_BATCH):
        if time.perf_counter() > deadline:
            return lo, kept, gained, "time cap"
        # drawn a batch at a time (the same stream as all at once): memory stays flat
        # whatever the budget of kicks
        batch = rng.integers(0, 2**62, size=(min(KICK_BATCH, kicks - lo), 3))
        won_kicks, won, visits = _kicks(
            m.poses, m.count, m.axes, neighbours.nodes, neighbours.times, path.nodes,
            path.pos, path.dirty, backup, queue, queued, batch, span,
        )  # fmt: skip
        kept += won_kicks
        gained += won
        show(visits)
    return kicks, kept, gained, "move budget"


# The compiled kernels. Node ids: targets 0..n-1, S = n, E = n + 1; the metric has
# n + 1 rows (E has none: every move into or out of it costs nothing).

_CONVERGED, _BUDGET, _SLICED = 0, 1, 2


@compiled
def _descend(
    poses: FloatArray,
    count: Ints,
    axes: FloatArray,
    nbr: Ints,
    nbr_t: FloatArray,
    nodes: Ints,
    pos: Ints,
    dirty: Ints,
    queue: Ints,
    ends: Ints,
    queued: BoolArray,
    max_moves: int,
    max_visits: int,
) -> tuple[int, float, int, int]:
    """Visit queued nodes (a ring buffer: ``ends`` its head and length) until the queue
    is empty (converged), ``max_moves`` improving moves were applied (the budget) or
    ``max_visits`` nodes were visited (a slice). (moves, gained, visits, status)."""
    moves, gained, visits = 0, 0.0, 0
    size = len(queue)
    while ends[1] > 0:
        if moves >= max_moves:
            return moves, gained, visits, _BUDGET
        if visits >= max_visits:
            return moves, gained, visits, _SLICED
        a = queue[ends[0]]
        ends[0] = (ends[0] + 1) % size
        ends[1] -= 1
        queued[a] = False
        visits += 1
        gain = two_opt(poses, count, axes, nbr, nbr_t, nodes, pos, dirty, queue, ends, queued, a)
        if gain == 0.0:
            gain = or_opt(poses, count, axes, nbr, nbr_t, nodes, pos, dirty, queue, ends, queued, a)
        if gain > 0.0:
            moves += 1
            gained += gain
    return moves, gained, visits, _CONVERGED


@compiled
def _kicks(
    poses: FloatArray,
    count: Ints,
    axes: FloatArray,
    nbr: Ints,
    nbr_t: FloatArray,
    nodes: Ints,
    pos: Ints,
    dirty: Ints,
    backup: Ints,
    queue: Ints,
    queued: BoolArray,
    draws: Ints,
    span: int,
) -> tuple[int, float, int]:
    """The kicks of ``draws`` (K, 3), each kept or undone from ``backup`` (the path as
    last kept). (kicks kept, gained, node visits)."""
    n = len(nodes) - 2
    kept, gained, visits = 0, 0.0, 0
    ends = np.zeros(2, dtype=np.int64)
    for k in range(len(draws)):
        lb, lc = 1 + draws[k, 1] % span, 1 + draws[k, 2] % span
        i = 1 + draws[k, 0] % (n - lb - lc + 1)  # B = i.., C = then lc nodes; E stays last
        j, m = i + lb, i + lb + lc
        a, b0, b1 = nodes[i - 1], nodes[i], nodes[j - 1]
        c0, c1, d = nodes[j], nodes[m - 1], nodes[m]
        delta = (
            cost(poses, count, axes, a, c0)
            + cost(poses, count, axes, c1, b0)
            + cost(poses, count, axes, b1, d)
            - cost(poses, count, axes, a, b0)
            - cost(poses, count, axes, b1, c0)
            - cost(poses, count, axes, c1, d)
        )
        write(nodes, pos, dirty, i, np.concatenate((nodes[j:m], nodes[i:j])))
        # A descent from the six nodes touched, in this order (a node twice if B or C
        # is one node long), the ends excluded.
        ends[0], ends[1] = 0, 0
        for u in (a, b0, b1, c0, c1, d):
            if u < n:
                queue[ends[1]] = u
                ends[1] += 1
                queued[u] = True
        won = 0.0
        while True:
            _, step, seen, status = _descend(
                poses, count, axes, nbr, nbr_t, nodes, pos, dirty, queue, ends, queued,
                1 << 62, 1 << 62,
            )  # fmt: skip
            won += step
            visits += seen
            if status == _CONVERGED:
                break
        lo, hi = dirty[0], dirty[1]
        if won - delta > EPSILON:
            kept += 1
            gained += won - delta
            backup[lo : hi + 1] = nodes[lo : hi + 1]
        else:
            nodes[lo : hi + 1] = backup[lo : hi + 1]
            for p in range(lo, hi + 1):
                pos[nodes[p]] = p
        dirty[0], dirty[1] = 1, 0
    return kept, gained, visits
