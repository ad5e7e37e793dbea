"""Points placed uniformly in a coordinate box: grid, stratified, Sobol, Halton, random.

Everything is generated on the unit cube [0, 1)^d and then scaled to the box, after
optional per-coordinate warps u ↦ u^p. Grids use cell centres (an unbiased, uniform
placement that avoids the box's degenerate faces), in C order.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from gonio.types import FloatArray


def grid_shape_for(target_per_axis: float, dims: int) -> tuple[int, ...]:
    """Equal counts per axis giving at least ``target_per_axis ** dims`` points."""
    return (max(1, int(np.ceil(target_per_axis))),) * dims


def grid(shape: tuple[int, ...], *, jitter: np.random.Generator | None = None) -> FloatArray:
    """Cell centres (or, with ``jitter``, one uniform point per cell) of a grid, C order."""
    axes = [np.arange(n, dtype=np.float64) for n in shape]
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(shape))
    offset = 0.5 if jitter is None else jitter.random(mesh.shape)
    return np.asarray((mesh + offset) / np.asarray(shape, dtype=np.float64), dtype=np.float64)


def serpentine(shape: tuple[int, ...]) -> np.ndarray:
    """The boustrophedon visiting order of a C-order grid (the reflected mixed-radix Gray
    code): each axis runs forward or backward by the parity of the path rank of the
    outer axes, so consecutive cells always differ by one step on one axis."""
    steps = np.unravel_index(np.arange(int(np.prod(shape))), shape)  # the path's counter
    rank = np.zeros_like(steps[0])
    cell = []
    for axis, n in enumerate(shape):
        step = steps[axis]
        cell.append(np.where(rank % 2 == 0, step, n - 1 - step) if axis else step)
        rank = rank * n + step
    return np.asarray(np.ravel_multi_index(tuple(cell), shape))


class Sequence:
    """An endless stream of unit-cube points of one strategy (sobol, halton, random)."""

    def __init__(self, strategy: str, dims: int, seed: int) -> None:
        self.strategy = strategy
        if strategy == "sobol":
            self._engine: qmc.QMCEngine | None = qmc.Sobol(dims, scramble=True, seed=seed)
        elif strategy == "halton":
            self._engine = qmc.Halton(dims, scramble=True, seed=seed)
        elif strategy == "random":
            self._engine = None
            self._rng = np.random.default_rng(seed)
        else:
            raise ValueError(f"{strategy} is not a sequence strategy")
        self.dims = dims

    def draw(self, n: int) -> FloatArray:
        if self._engine is None:
            return np.asarray(self._rng.random((n, self.dims)), dtype=np.float64)
        return np.asarray(self._engine.random(n), dtype=np.float64)


def to_box(unit: FloatArray, bounds: FloatArray, powers: FloatArray) -> FloatArray:
    """Unit-cube points (N, d) warped by ``powers`` (d,) and scaled to ``bounds`` (d, 2)."""
    warped = np.power(unit, powers)
    return np.asarray(bounds[:, 0] + warped * (bounds[:, 1] - bounds[:, 0]), dtype=np.float64)
