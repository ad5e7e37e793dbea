"""`blockwise`: a row-wise function run on bounded blocks gives what one call gives."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.blocks import blockwise
from gonio.types import FloatArray


def pieces(x: FloatArray, y: FloatArray) -> tuple[FloatArray, np.ndarray]:
    """A row-wise function of rows (M, 3) and (M,) with two outputs of other shapes."""
    return np.cumsum(x, axis=1) * y[:, None], np.argmax(x, axis=1).astype(np.int8)


@settings(max_examples=60, deadline=None)
@given(rows=st.integers(0, 300), size=st.integers(1, 400), seed=st.integers(0, 2**32 - 1))
def test_blocks_join_to_the_whole(rows: int, size: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    x, y = rng.normal(size=(rows, 3)), rng.normal(size=rows)
    calls: list[int] = []

    def counted(x: FloatArray, y: FloatArray) -> tuple[FloatArray, np.ndarray]:
        calls.append(len(x))
        return pieces(x, y)

    whole = pieces(x, y)
    blocked = blockwise(counted, x, y, size=size)
    assert len(blocked) == 2
    for got, expected in zip(blocked, whole, strict=True):
        assert got.dtype == expected.dtype and got.shape == expected.shape
        assert got.tobytes() == expected.tobytes()
    assert max(calls) <= size and sum(calls) == rows
    assert len(calls) == max(1, -(-rows // size))


def test_a_single_array_result_and_a_small_batch_pass_through_unchanged() -> None:
    x = np.arange(12.0).reshape(6, 2)
    seen: list[FloatArray] = []

    def double(a: FloatArray) -> FloatArray:
        seen.append(a)
        return 2.0 * a

    assert np.array_equal(blockwise(double, x, size=4), 2.0 * x)
    assert [len(a) for a in seen] == [4, 2]
    seen.clear()
    assert np.array_equal(blockwise(double, x, size=6), 2.0 * x)
    assert seen[0] is x  # one call, the very array


def test_a_bad_size_or_ragged_arrays_are_refused() -> None:
    with pytest.raises(ValueError, match="positive"):
        blockwise(np.negative, np.zeros(3), size=0)
    with pytest.raises(ValueError, match="one length, got 3, 4"):
        blockwise(np.add, np.zeros(3), np.zeros(4))
