"""The fixed, seeded test set of direction pairs a reconstruction is scored on
(docs/explanations/evaluation.md).

Each of ωi and ωo is drawn independently and uniformly in solid angle over the cap
θ ≤ θmax of the rig (cos θ uniform in [cos θmax, 1], φ uniform in [0, 2π)), so the pairs
are uniform in the product measure dωi dωo; pairs the rig cannot measure (blind spot,
footprint, axis limits, collisions: `Rig.reachable`) are dropped and more are drawn until
``size`` remain. The same rig, isotropy, size and seed give the same pairs, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.directions import uniform_cap
from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.types import FloatArray

#: Pairs in the default test set.
DEFAULT_SIZE = 20_000
#: The default test set's seed (a fixed number: every evaluation scores the same pairs).
DEFAULT_SEED = 14
#: Draws are made in batches of this many times the pairs still missing …
_OVERDRAW = 2.0
#: … and at most this many batches: a rig that measures almost nothing is an error.
_MAX_BATCHES = 64


@dataclass(frozen=True)
class TestSet:
    """Pairs (N, 3) each, unit directions in the sample frame, and how they were drawn."""

    __test__ = False  # not a pytest class, despite its name

    wi: FloatArray
    wo: FloatArray
    seed: int
    drawn: int  # pairs drawn in all (the last batch's surplus included)

    def __len__(self) -> int:
        return len(self.wi)


def draw(
    rig: Rig, *, isotropic: bool, size: int = DEFAULT_SIZE, seed: int = DEFAULT_SEED
) -> TestSet:
    """``size`` pairs uniform in dωi dωo over what ``rig`` measures (see the module);
    ``isotropic``: as the run was planned (the rig may then turn a pair about the normal
    to reach it). `GonioError` if the rig reaches too few pairs to fill the set."""
    if size < 1:
        raise GonioError(f"a test set needs at least one pair, got {size}")
    rng = np.random.default_rng(seed)
    kept_wi: list[FloatArray] = []
    kept_wo: list[FloatArray] = []
    kept = drawn = 0
    for _ in range(_MAX_BATCHES):
        if kept >= size:
            break
        n = max(int(_OVERDRAW * (size - kept)), 256)
        wi = uniform_cap(rng, n, rig.theta_max)
        wo = uniform_cap(rng, n, rig.theta_max)
        ok, _ = rig.reachable(wi, wo, isotropic=isotropic)
        kept_wi.append(wi[ok])
        kept_wo.append(wo[ok])
        kept += int(np.count_nonzero(ok))
        drawn += n
    if kept < size:
        raise GonioError(
            f"the rig {rig.spec.name!r} measures only {kept} of {drawn} pairs drawn; "
            f"too few for a test set of {size}"
        )
    wi_all, wo_all = np.concatenate(kept_wi), np.concatenate(kept_wo)
    return TestSet(wi=wi_all[:size], wo=wo_all[:size], seed=seed, drawn=drawn)
