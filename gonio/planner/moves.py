"""The moves of the local search on an open path, compiled (numba): the move time between
two nodes (each axis on its trapezoidal profile, `gonio.rig.travel.TravelModel`'s
arithmetic bit for bit), the path's arrays and their edits (a block written, a stretch
reversed, a segment moved; every position written noted for an exact undo), and the
two moves from a node, 2-opt and Or-opt, each taking the first improvement over the
node's neighbour list and waking the nodes it touched. `gonio.planner.search` runs them.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from gonio.planner.jit import compiled
from gonio.types import BoolArray, FloatArray

Ints = npt.NDArray[np.int64]

#: Improvements smaller than this (s) are not moves: they would cycle on rounding.
EPSILON = 1e-9


@compiled
def axis_time(axes: FloatArray, j: int, d: float) -> float:
    """Axis j's time (s) to move d ≥ 0 rad, ``axes`` a `Metric`'s: 2 √(d / a) short of
    the cruise speed, d / v + v / a past it (`TravelModel.time`, bit for bit)."""
    if d < axes[2, j]:
        return 2.0 * math.sqrt(d / axes[1, j])
    return float(d / axes[0, j] + axes[3, j])


@compiled
def cost(poses: FloatArray, count: Ints, axes: FloatArray, u: int, v: int) -> float:
    """The move time between nodes u and v (0 at E)."""
    m = poses.shape[0]
    if u >= m or v >= m:
        return 0.0
    best = np.inf
    for p in range(count[u]):
        for q in range(count[v]):
            worst = 0.0
            for j in range(poses.shape[2]):
                x, y = poses[u, p, j], poses[v, q, j]
                t = axis_time(axes, j, x - y if x > y else y - x)
                if t > worst:
                    worst = t
            if worst < best:
                best = worst
    return best


@compiled
def times(poses: FloatArray, count: Ints, axes: FloatArray, u: Ints, v: Ints) -> FloatArray:
    out = np.empty(len(u))
    for i in range(len(u)):
        out[i] = cost(poses, count, axes, u[i], v[i])
    return out


@compiled
def write(nodes: Ints, pos: Ints, dirty: Ints, lo: int, block: Ints) -> None:
    """Write ``block`` at positions lo.. and mark them dirty."""
    for k in range(len(block)):
        nodes[lo + k] = block[k]
        pos[block[k]] = lo + k
    hi = lo + len(block) - 1
    if dirty[1] < dirty[0]:
        dirty[0], dirty[1] = lo, hi
    else:
        dirty[0] = min(dirty[0], lo)
        dirty[1] = max(dirty[1], hi)


@compiled
def _reverse(nodes: Ints, pos: Ints, dirty: Ints, lo: int, hi: int) -> None:
    write(nodes, pos, dirty, lo, nodes[lo : hi + 1][::-1].copy())


@compiled
def _move_segment(
    nodes: Ints, pos: Ints, dirty: Ints, i: int, length: int, after: int, flip: bool
) -> None:
    """Move the nodes at positions i..i+length-1 to follow the node now at position
    ``after`` (outside the segment), reversed if ``flip``."""
    segment = nodes[i : i + length].copy()
    if flip:
        segment = segment[::-1].copy()
    if after < i:  # the segment moves back: the nodes in between shift forward
        block = np.concatenate((segment, nodes[after + 1 : i]))
        write(nodes, pos, dirty, after + 1, block)
    else:  # the segment moves forward
        block = np.concatenate((nodes[i + length : after + 1], segment))
        write(nodes, pos, dirty, i, block)


@compiled
def _wake(queue: Ints, ends: Ints, queued: BoolArray, u: int) -> None:
    if not queued[u]:
        queued[u] = True
        queue[(ends[0] + ends[1]) % len(queue)] = u
        ends[1] += 1


@compiled
def two_opt(
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
    a: int,
) -> float:
    i = pos[a]
    # Successor side: drop (a, a+), (c, c+); add (a, c), (a+, c+).
    b = nodes[i + 1]
    d_ab = cost(poses, count, axes, a, b)
    for k in range(nbr.shape[1]):
        c = nbr[a, k]
        if c < 0:
            break
        g1 = d_ab - nbr_t[a, k]
        if g1 <= EPSILON:
            break
        if c == b:  # (c is never E: E is in no neighbour list)
            continue
        j = pos[c]
        d = nodes[j + 1]
        if d == a:
            continue
        gain = g1 + cost(poses, count, axes, c, d) - cost(poses, count, axes, b, d)
        if gain > EPSILON:
            if j > i:
                _reverse(nodes, pos, dirty, i + 1, j)
            else:
                _reverse(nodes, pos, dirty, j + 1, i)
            for w in (a, b, c, d):
                _wake(queue, ends, queued, w)
            return float(gain)
    # Predecessor side: drop (a-, a), (c-, c); add (a, c), (a-, c-).
    b = nodes[i - 1]
    d_ab = cost(poses, count, axes, b, a)
    for k in range(nbr.shape[1]):
        c = nbr[a, k]
        if c < 0:
            break
        g1 = d_ab - nbr_t[a, k]
        if g1 <= EPSILON:
            break
        j = pos[c]
        if c == b or j == 0:
            continue
        d = nodes[j - 1]
        if d == a:
            continue
        gain = g1 + cost(poses, count, axes, d, c) - cost(poses, count, axes, b, d)
        if gain > EPSILON:
            if j > i:
                _reverse(nodes, pos, dirty, i, j - 1)
            else:
                _reverse(nodes, pos, dirty, j, i - 1)
            for w in (a, b, c, d):
                _wake(queue, ends, queued, w)
            return float(gain)
    return 0.0


@compiled
def or_opt(
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
    a: int,
) -> float:
    n = len(nodes) - 2
    i0 = pos[a]
    for length in range(1, 4):
        for side in range(2 if length > 1 else 1):  # segments starting or ending at a
            i = i0 if side == 0 else i0 - length + 1
            if i < 1 or i + length > n + 1:
                continue
            first, last = nodes[i], nodes[i + length - 1]
            p, q = nodes[i - 1], nodes[i + length]
            removed = (
                cost(poses, count, axes, p, first)
                + cost(poses, count, axes, last, q)
                - cost(poses, count, axes, p, q)
            )
            if removed <= EPSILON:
                continue
            for which in range(2 if length > 1 else 1):
                end = first if which == 0 else last
                head, tail = end, first if end == last else last
                for k in range(nbr.shape[1]):
                    c = nbr[end, k]
                    if c < 0:
                        break
                    g1 = removed - nbr_t[end, k]
                    if g1 <= EPSILON:
                        break
                    j = pos[c]
                    if i <= j < i + length:
                        continue
                    # Insert between c and its successor, then its predecessor.
                    for option in range(2):
                        if option == 0:
                            x, y, after = c, nodes[j + 1] if j <= n else -1, j
                        else:
                            x, y, after = nodes[j - 1] if j >= 1 else -1, c, j - 1
                        if x < 0 or y < 0:  # S first and E last: never between
                            continue
                        if i <= pos[x] < i + length or i <= pos[y] < i + length:
                            continue
                        # `end` sits next to c; the other end goes to the other side.
                        if option == 0:
                            added = (
                                cost(poses, count, axes, x, head)
                                + cost(poses, count, axes, tail, y)
                                - cost(poses, count, axes, x, y)
                            )
                            flip = head != first
                        else:
                            added = (
                                cost(poses, count, axes, x, tail)
                                + cost(poses, count, axes, head, y)
                                - cost(poses, count, axes, x, y)
                            )
                            flip = tail != first
                        if removed - added > EPSILON:
                            segment = nodes[i : i + length].copy()
                            _move_segment(nodes, pos, dirty, i, length, after, flip)
                            for w in (p, q, x, y):
                                _wake(queue, ends, queued, w)
                            for w in segment:
                                _wake(queue, ends, queued, w)
                            return removed - added
    return 0.0
