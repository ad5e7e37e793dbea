"""`Rig.solve` and `Rig.reachable` run their pairs in blocks (`gonio.blocks`): a batch
spanning several blocks gives, bit for bit, what its pairs give solved in pieces of any
size (one block each), on pairs over the whole sphere (below the horizon too)."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.blocks import BLOCK
from gonio.rig.model import Rig
from gonio.types import FloatArray
from tests.conftest import RIG_NAMES

#: More pairs than two blocks hold, so the batch is cut at two places.
PAIRS = 2 * BLOCK + 123


def sphere(rng: np.random.Generator, n: int) -> FloatArray:
    """Directions (n, 3) uniform on the sphere, with the normal and the horizon among them."""
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    w[:7] = [
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
        [-0.0, 0.0, 1.0],
        [0.6, 0.8, 0.0],
        [0.0, 0.0, -1.0],
        [0.28, 0.0, 0.96],
    ]
    return w


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@settings(max_examples=4, deadline=None)
@given(
    name=st.sampled_from(RIG_NAMES),
    isotropic=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
    cuts=st.lists(st.integers(1, PAIRS - 1), max_size=6),
)
def test_a_batch_is_solved_as_its_pieces_are(
    rigs: dict[str, Rig], name: str, isotropic: bool, seed: int, cuts: list[int]
) -> None:
    rig = rigs[name]
    rng = np.random.default_rng(seed)
    wi, wo = sphere(rng, PAIRS), sphere(rng, PAIRS)
    wo[10:20] = wi[10:20]  # retro-reflection
    wo[20:30] = wi[20:30] * [-1.0, -1.0, 1.0]  # the mirror direction
    bounds = sorted({0, PAIRS, *cuts, *range(0, PAIRS, BLOCK - 1)})
    spans = list(itertools.pairwise(bounds))
    whole = rig.solve(wi, wo, isotropic=isotropic)
    parts = [rig.solve(wi[a:b], wo[a:b], isotropic=isotropic) for a, b in spans]
    for field in ("angles", "wi", "wo", "reasons", "candidates", "usable"):
        joined = np.concatenate([getattr(p, field) for p in parts])
        assert same(getattr(whole, field), joined), field
    mask, reasons = rig.reachable(wi, wo, isotropic=isotropic)
    pieces = [rig.reachable(wi[a:b], wo[a:b], isotropic=isotropic) for a, b in spans]
    assert same(mask, np.concatenate([p[0] for p in pieces]))
    assert same(reasons, np.concatenate([p[1] for p in pieces]))
    assert same(reasons, whole.reasons)
