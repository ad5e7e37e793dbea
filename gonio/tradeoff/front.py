"""The trade-off read from a sweep's rows: the Pareto front of error against instrument
time, and the fastest combination meeting an error target.

Only rows with both figures count (a failed combination, or a metric with no pair
scored, has none). A row is on the front when no other row is at least as fast and at
least as accurate and better in one of the two; of rows with the same time and error
the first (in the order given) stands for all.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

#: The time a front is drawn against: the simulated instrument time (s).
TIME = "instrument_s"


def _usable(row: dict[str, Any], metric: str) -> bool:
    t, e = row.get(TIME), row.get(metric)
    return isinstance(t, int | float) and isinstance(e, int | float) and math.isfinite(t + e)


def pareto_front(rows: Sequence[dict[str, Any]], metric: str) -> list[int]:
    """Indices of the rows on the front of ``metric`` against `TIME`, fastest first."""
    order = sorted(
        (i for i, r in enumerate(rows) if _usable(r, metric)),
        key=lambda i: (rows[i][TIME], rows[i][metric], i),
    )
    front: list[int] = []
    best = math.inf
    for i in order:
        if rows[i][metric] < best:
            front.append(i)
            best = rows[i][metric]
    return front


def fastest_meeting(
    rows: Sequence[dict[str, Any]], metric: str, target: float
) -> dict[str, Any] | None:
    """The row with the least `TIME` whose ``metric`` is at most ``target`` (ties: the
    lower error, then the first given); None if no row meets it."""
    meeting = [
        (r[TIME], r[metric], i)
        for i, r in enumerate(rows)
        if _usable(r, metric) and r[metric] <= target
    ]
    return rows[min(meeting)[2]] if meeting else None


def best(rows: Sequence[dict[str, Any]], metric: str) -> dict[str, Any] | None:
    """The row with the lowest ``metric`` (ties: the faster, then the first given)."""
    scored = [(r[metric], r[TIME], i) for i, r in enumerate(rows) if _usable(r, metric)]
    return rows[min(scored)[2]] if scored else None
