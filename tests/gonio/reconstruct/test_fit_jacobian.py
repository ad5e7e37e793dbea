"""The fit's Jacobian (`gonio.reconstruct.fit._jacobian`): the three channels of a colour
parameter stepped at once give the columns each stepped alone gives, bit for bit, in
one evaluation per parameter, also where a step meets a bound."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.brdf import parse
from gonio.reconstruct.fit import _jacobian

STEP = np.finfo(np.float64).eps ** 0.5


def directions(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def one_at_a_time(residuals, x, r, low, high) -> np.ndarray:
    """Forward differences stepping one parameter at a time: √ε·max(1, |x|), turned back
    where it would cross a bound and there is room behind, else the room to the bound."""
    out = np.empty((len(r), len(x)))
    for i in range(len(x)):
        h = STEP * (1.0 if x[i] >= 0.0 else -1.0) * max(1.0, abs(x[i]))
        below, above = x[i] - low[i], high[i] - x[i]
        if abs(h) > max(below, above):
            h = above if above >= below else -below
        elif not low[i] <= x[i] + h <= high[i]:
            h = -h
        stepped = x.copy()
        stepped[i] = x[i] + h
        out[:, i] = (residuals(stepped) - r) / (stepped[i] - x[i])
    return out


@pytest.mark.parametrize("spec", ["ggx:fresnel=conductor", "lambert+ggx", "lambert+ggx+ggx"])
@pytest.mark.parametrize("where", ["inside", "low", "high"])
def test_grouped_columns_are_the_single_steps(spec: str, where: str) -> None:
    family = parse(spec)
    slots = family.slots(True)
    wi, wo = directions(40, 1), directions(40, 2)
    calls = []

    def residuals(x: np.ndarray) -> np.ndarray:
        calls.append(1)
        return np.asarray(family.model(slots, x).eval(wi, wo), dtype=np.float64).ravel()

    low = np.array([s.low for s in slots])
    high = np.array([s.high for s in slots])
    x = np.clip(np.linspace(0.2, 1.7, len(slots)), low, high)
    if where == "low":
        x = low + 1e-12
    elif where == "high":
        x = np.where(np.isfinite(high), high - 1e-12, x)
    r = residuals(x)
    calls.clear()
    got = _jacobian(residuals, x, r, slots, low, high, 3)
    groups = len({i if s.channel is None else (s.term, s.param) for i, s in enumerate(slots)})
    assert len(calls) == groups < len(slots)
    np.testing.assert_array_equal(got, one_at_a_time(residuals, x, r, low, high))
    assert np.count_nonzero(got) > 0
