"""Row-wise math applied to bounded blocks of rows: the one place a long batch of pairs
is cut into pieces.

A vectorized function of N rows (direction pairs, scaled points) allocates temporaries
several times its input's size. Up to some ten thousand rows they stay in the
processor's caches and the allocator's free lists; at a million rows each is a fresh
mapping of tens or hundreds of megabytes, paid for in page faults and memory traffic
(`Rig.reachable` ran 20 times slower per pair at 10⁶ pairs than at 10⁵). `blockwise`
runs such a function on consecutive blocks of at most ``size`` rows and joins the
results, so the cost per row stays flat. It is exact for a function whose every output
row depends only on its own input rows (anything else is not row-wise and must not be
blocked).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

import numpy as np

#: Rows per block unless a caller says otherwise.
BLOCK = 1 << 14

Out = TypeVar("Out")


def blockwise(fn: Callable[..., Out], *arrays: Any, size: int = BLOCK) -> Out:
    """``fn(*arrays)`` computed on blocks of at most ``size`` rows.

    Parameters
    ----------
    fn : callable
        A row-wise function: called with one block of each of ``arrays`` (their rows
        ``start:start + size``), it returns an array, or a tuple of arrays, with one row
        per input row.
    *arrays : array_like
        Arrays of one length along their first axis (the rows).
    size : int
        The largest block, in rows (positive).

    Returns
    -------
    array or tuple of arrays
        What ``fn`` returns, the blocks' results joined along their first axis; at most
        ``size`` rows go to ``fn`` in one call, unchanged (no copy, no join).
    """
    if size < 1:
        raise ValueError(f"size: expected a positive number of rows, got {size}")
    columns = [np.asarray(a) for a in arrays]
    if not columns:
        raise ValueError("blockwise: expected at least one array")
    rows = len(columns[0])
    if any(len(a) != rows for a in columns):
        lengths = ", ".join(str(len(a)) for a in columns)
        raise ValueError(f"blockwise: expected arrays of one length, got {lengths}")
    if rows <= size:
        return fn(*columns)
    parts: list[Any] = [
        fn(*(a[start : start + size] for a in columns)) for start in range(0, rows, size)
    ]
    first = parts[0]
    if isinstance(first, tuple):
        joined = tuple(np.concatenate([p[k] for p in parts]) for k in range(len(first)))
        return cast(Out, joined)
    return cast(Out, np.concatenate(parts))


__all__ = ["BLOCK", "blockwise"]
