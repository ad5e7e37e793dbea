"""Local search on an open path: 2-opt and Or-opt descent, and iterated local search.

The path starts at a fixed node S and ends at a free end E (every move into E costs
nothing), so it is an open path from S. Costs come from a function of two node ids
(`Cost`): the travel time between fixed poses, or the relaxed any-branch time
(`gonio.planner.poses.Relaxed`).

- `descend`: 2-opt and Or-opt (segments of 1 to 3, either orientation) from each node
  in a queue, over neighbour lists, first improvement, don't-look bits; until no move
  gains more than `EPSILON`, a budget of improving moves is spent, or a deadline passes.
- `iterate`: kicks, each a double bridge within a window of the path (two adjacent
  segments of random lengths ≤ `KICK_SPAN` swapped), followed by a descent from the six
  nodes it touched; kept if the path got shorter by more than `EPSILON`, otherwise
  undone exactly (a journal of the blocks written). Kicks are drawn from a seeded
  `numpy.random.Generator`, so a seed and a kick budget give the same path anywhere.

The search is sequential by nature (each move changes the next one's costs), so it runs
as a Python loop with scalar costs; the path lives in numpy arrays (block writes).
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Literal

import numpy as np

from gonio.progress import Progress, Quiet
from gonio.rig.travel import TravelModel
from gonio.types import FloatArray

#: Cost of moving from one node to another (s); node ids are the targets 0..n-1 and the
#: start n (the free end is handled by the path).
Cost = Callable[[int, int], float]
#: Each node's neighbours, nearest first, with the move time to each: [(node, s), …].
Neighbours = list[list[tuple[int, float]]]
#: Why a search stopped (only the last depends on the machine).
Stop = Literal["converged", "move budget", "time cap"]

#: Improvements smaller than this (s) are not moves: they would cycle on rounding.
EPSILON = 1e-9
#: The longest segment a kick moves (targets).
KICK_SPAN = 30
#: Move times remembered (pairs) before the memo starts again.
CACHE = 2_000_000


def path_time(model: TravelModel, start: FloatArray, targets: FloatArray) -> float:
    """Travel time (s) from ``start`` through ``targets`` (N, A) in the given order."""
    if len(targets) == 0:
        return 0.0
    previous = np.vstack([np.asarray(start, dtype=np.float64)[None, :], targets[:-1]])
    return float(model.time(previous, targets).sum())


class Path:
    """An open path: node S (the start, id n) first, node E (id n + 1, a free end) last,
    targets 0..n-1 in between. ``cost(u, v)`` is the move time; moves into or out of E
    cost nothing."""

    def __init__(self, n: int, order: np.ndarray, cost: Cost):
        self.n = n
        self.S, self.E = n, n + 1
        self.nodes = np.concatenate([[self.S], order, [self.E]]).astype(np.int64)
        self.pos = np.empty(n + 2, dtype=np.int64)
        self.pos[self.nodes] = np.arange(n + 2)
        end, width = self.E, n + 2
        #: Blocks written since the journal was opened: (first position, old nodes).
        self.journal: list[tuple[int, np.ndarray]] | None = None
        memo: dict[int, float] = {}

        def edge(u: int, v: int) -> float:
            # The metric is symmetric: one entry per unordered pair, computed once
            # (cleared when full: the local search revisits the same few pairs).
            if u == end or v == end:
                return 0.0
            key = u * width + v if u < v else v * width + u
            t = memo.get(key)
            if t is None:
                if len(memo) >= CACHE:
                    memo.clear()
                t = memo[key] = cost(u, v)
            return t

        self.cost = edge

    def order(self) -> np.ndarray:
        """The targets in visiting order (a copy)."""
        return self.nodes[1:-1].copy()

    def length(self) -> float:
        """The path's time (s), summed in order."""
        nodes = self.nodes.tolist()
        return float(sum(self.cost(u, v) for u, v in itertools.pairwise(nodes)))

    def _write(self, lo: int, block: np.ndarray) -> None:
        if self.journal is not None:
            self.journal.append((lo, self.nodes[lo : lo + len(block)].copy()))
        self.nodes[lo : lo + len(block)] = block
        self.pos[block] = np.arange(lo, lo + len(block))

    def undo(self) -> None:
        """Restore the path as it was when the journal was opened."""
        assert self.journal is not None
        for lo, old in reversed(self.journal):
            self.nodes[lo : lo + len(old)] = old
            self.pos[old] = np.arange(lo, lo + len(old))
        self.journal = []

    def reverse(self, lo: int, hi: int) -> None:
        """Reverse the nodes at positions lo..hi (inclusive)."""
        self._write(lo, self.nodes[lo : hi + 1][::-1].copy())

    def move_segment(self, i: int, length: int, after: int, flip: bool) -> None:
        """Move the nodes at positions i..i+length-1 to follow the node now at position
        ``after`` (outside the segment), reversed if ``flip``."""
        nodes = self.nodes
        segment = nodes[i : i + length].copy()
        if flip:
            segment = segment[::-1]
        if after < i:  # the segment moves back: the nodes in between shift forward
            self._write(after + 1, np.concatenate([segment, nodes[after + 1 : i]]))
        else:  # the segment moves forward
            self._write(i, np.concatenate([nodes[i + length : after + 1], segment]))


def descend(
    path: Path,
    neighbours: Neighbours,
    max_moves: int,
    deadline: float,
    queue_from: Iterable[int] | None = None,
    shown: Progress | None = None,
) -> tuple[int, float, Stop]:
    """2-opt and Or-opt moves from each queued node (default: every target in index
    order), until none improves, ``max_moves`` have been applied or ``deadline``
    (`time.perf_counter`) has passed. Returns (moves applied, time gained (s), why it
    stopped).

    Deterministic but for the deadline: neighbours are visited nearest first, the first
    improving move found is applied, a move wakes the nodes at its ends. Each node visit
    costs a bounded number of cost evaluations, so ``max_moves`` bounds the work too.
    ``shown`` counts the node visits (`gonio.progress`).
    """
    cost, pos, nodes = path.cost, path.pos, path.nodes
    at, node = pos.item, nodes.item  # Python ints, faster than int(array[i])
    S, E, n = path.S, path.E, path.n
    nbr = neighbours
    queue = deque(range(n) if queue_from is None else (u for u in queue_from if u < n))
    queued = np.zeros(n + 2, dtype=np.bool_)
    queued[list(queue)] = True
    queued[[S, E]] = True  # the ends never enter the queue
    moves, gained, visits = 0, 0.0, 0
    show = (Quiet() if shown is None else shown).advance

    def wake(*nodes_: int) -> None:
        for u in nodes_:
            if not queued[u]:
                queued[u] = True
                queue.append(u)

    def two_opt(a: int) -> float:
        i = at(a)
        # Successor side: drop (a, a+), (c, c+); add (a, c), (a+, c+).
        b = node(i + 1)
        d_ab = cost(a, b)
        for c, t_ac in nbr[a]:
            g1 = d_ab - t_ac
            if g1 <= EPSILON:
                break
            if c == b:  # (c is never E: E is in no neighbour list)
                continue
            j = at(c)
            d = node(j + 1)
            if d == a:
                continue
            gain = g1 + cost(c, d) - cost(b, d)
            if gain > EPSILON:
                lo, hi = (i + 1, j) if j > i else (j + 1, i)
                path.reverse(lo, hi)
                wake(a, b, c, d)
                return gain
        # Predecessor side: drop (a-, a), (c-, c); add (a, c), (a-, c-).
        b = node(i - 1)
        d_ab = cost(b, a)
        for c, t_ac in nbr[a]:
            g1 = d_ab - t_ac
            if g1 <= EPSILON:
                break
            j = at(c)
            if c == b or j == 0:
                continue
            d = node(j - 1)
            if d == a:
                continue
            gain = g1 + cost(d, c) - cost(b, d)
            if gain > EPSILON:
                lo, hi = (i, j - 1) if j > i else (j, i - 1)
                path.reverse(lo, hi)
                wake(a, b, c, d)
                return gain
        return 0.0

    def or_opt(a: int) -> float:
        i0 = at(a)
        for length in (1, 2, 3):
            for i in (i0, i0 - length + 1):  # segments starting or ending at a
                if i < 1 or i + length > n + 1 or (length == 1 and i != i0):
                    continue
                segment = nodes[i : i + length].tolist()
                first, last = segment[0], segment[-1]
                p, q = node(i - 1), node(i + length)
                removed = cost(p, first) + cost(last, q) - cost(p, q)
                if removed <= EPSILON:
                    continue
                for end in (first, last):
                    for c, t_ec in nbr[end]:
                        g1 = removed - t_ec
                        if g1 <= EPSILON:
                            break
                        j = at(c)
                        if i <= j < i + length:
                            continue
                        # Insert between c and its successor, then its predecessor.
                        for x, y, after in (
                            (c, node(j + 1) if j <= n else -1, j),
                            (node(j - 1) if j >= 1 else -1, c, j - 1),
                        ):
                            if x < 0 or y < 0:  # S first and E last: never between
                                continue
                            if i <= at(x) < i + length or i <= at(y) < i + length:
                                continue
                            # `end` sits next to c; the other end goes to the other side.
                            head, tail = (end, first if end == last else last)
                            if x == c:
                                added = cost(x, head) + cost(tail, y) - cost(x, y)
                                flip = head != first
                            else:
                                added = cost(x, tail) + cost(head, y) - cost(x, y)
                                flip = tail != first
                            if removed - added > EPSILON:
                                path.move_segment(i, length, after, flip)
                                wake(p, q, x, y, *segment)
                                return removed - added
        return 0.0

    while queue:
        if moves >= max_moves:
            return moves, gained, "move budget"
        if time.perf_counter() > deadline:
            return moves, gained, "time cap"
        a = queue.popleft()
        queued[a] = False
        visits += 1
        if visits & 4095 == 0:
            show(4096)
        gain = two_opt(a) or or_opt(a)
        if gain > 0.0:
            moves += 1
            gained += gain
    return moves, gained, "converged"


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
    (s), why it stopped: "move budget" when the kicks ran out, or "time cap").

    A kick swaps two adjacent segments B, C of lengths in 1..`KICK_SPAN` (A B C D →
    A C B D: a double bridge, the move 2-opt and Or-opt cannot undo in one step). The
    descent after a kick may apply any number of moves; each is one pass of `descend`.
    """
    n = path.n
    if n < 3:
        return 0, 0, 0.0, "converged"
    cost, nodes = path.cost, path.nodes
    node = nodes.item
    span = min(KICK_SPAN, max(1, (n - 1) // 2))
    draws = rng.integers(0, 2**62, size=(kicks, 3))
    kept, gained = 0, 0.0
    for k in range(kicks):
        if time.perf_counter() > deadline:
            return k, kept, gained, "time cap"
        r0, r1, r2 = draws[k].tolist()
        lb, lc = 1 + r1 % span, 1 + r2 % span
        i = 1 + r0 % (n - lb - lc + 1)  # B = i..i+lb-1, C = then lc nodes; E stays last
        j, m = i + lb, i + lb + lc
        a, b0, b1 = node(i - 1), node(i), node(j - 1)
        c0, c1, d = node(j), node(m - 1), node(m)
        delta = cost(a, c0) + cost(c1, b0) + cost(b1, d) - cost(a, b0) - cost(b1, c0) - cost(c1, d)
        path.journal = []
        path._write(i, np.concatenate([nodes[j:m], nodes[i:j]]))
        touched = (a, b0, b1, c0, c1, d)
        _, won, stop = descend(path, neighbours, 1 << 62, deadline, touched, shown)
        if won - delta > EPSILON:
            kept += 1
            gained += won - delta
        else:
            path.undo()
        path.journal = None
        if stop == "time cap":
            return k + 1, kept, gained, "time cap"
    return kicks, kept, gained, "move budget"
