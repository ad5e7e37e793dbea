"""Samples of a grid plan (strategy ``grid``): recognizing the grid from the measured
coordinates, and multilinear interpolation on it with scipy's RegularGridInterpolator.

Measured coordinates come from read-back angles, so they scatter around the planned
nodes by the motors' resolution and position error. An axis's values are split into
nodes wherever two sorted values differ by more than `NODE_TOLERANCE` (scaled units:
0.5 % of the axis); the samples form a grid when every axis has at least two nodes
well apart (each node's spread under half the smallest gap between nodes), no two
samples share a node tuple, and at least `MIN_OCCUPANCY` of the node tuples were
measured (a grid plan keeps the valid, reachable cells of its box). A node's coordinate
is the mean of its samples'.

Nodes the plan did not measure are NaN; so is the value at any query whose cell has
such a corner (the query is not supported). Seams are padded with one node beyond each
periodic azimuth and one mirrored node below each pole, their values taken from the
node they are copies of (`Space.canonical`) when there is one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from gonio.errors import GonioError
from gonio.reconstruct.coordinates import Space
from gonio.reconstruct.interpolants import Interpolant
from gonio.types import BoolArray, FloatArray

#: Largest gap (scaled units) between two measured values of one node.
NODE_TOLERANCE = 5e-3
#: Fewest measured node tuples, as a fraction of the grid's, for samples to be a grid.
MIN_OCCUPANCY = 0.05


@dataclass(frozen=True)
class Grid:
    """The nodes of each axis (scaled) and each sample's node indices (N, d)."""

    axes: tuple[FloatArray, ...]
    index: np.ndarray


def detect(x: FloatArray) -> Grid | None:
    """The grid the scaled sample coordinates ``x`` (N, d) lie on, or None."""
    axes, columns = [], []
    for values in x.T:
        order = np.argsort(values)
        ordered = values[order]
        starts = np.flatnonzero(np.diff(ordered) > NODE_TOLERANCE) + 1
        step = np.zeros(len(values), dtype=np.intp)
        step[starts] = 1
        label = np.empty(len(values), dtype=np.intp)
        label[order] = np.cumsum(step)
        nodes = np.bincount(label, weights=values) / np.bincount(label)
        spread = np.zeros(len(nodes))
        np.maximum.at(spread, label, np.abs(values - nodes[label]))
        if len(nodes) < 2 or 2.0 * spread.max() >= 0.5 * np.diff(nodes).min():
            return None
        axes.append(nodes)
        columns.append(label)
    index = np.stack(columns, axis=1)
    cells = int(np.prod([len(a) for a in axes]))
    flat = np.ravel_multi_index(index.T, tuple(len(a) for a in axes))
    if len(np.unique(flat)) < len(x) or len(x) < MIN_OCCUPANCY * cells:
        return None
    return Grid(tuple(axes), index)


class GridInterpolant(Interpolant):
    """Multilinear interpolation of a table (N, K) given at the nodes of ``grid``."""

    def __init__(self, grid: Grid, table: FloatArray, space: Space) -> None:
        shape = tuple(len(a) for a in grid.axes)
        values = np.full((*shape, table.shape[1]), np.nan)
        values[tuple(grid.index.T)] = table
        axes = [np.asarray(a) for a in grid.axes]
        pad = [(0, 0)] * space.dims
        for axis, period in space.periods:
            a = axes[axis]
            axes[axis] = np.concatenate([[a[-1] - period], a, [a[0] + period]])
            pad[axis] = (1, 1)
        for radial, _ in space.poles:
            if pad[radial] == (0, 0) and axes[radial][0] > 0.0:
                axes[radial] = np.concatenate([[-axes[radial][0]], axes[radial]])
                pad[radial] = (1, 0)
        values = np.pad(values, [*pad, (0, 0)], constant_values=np.nan)
        _fill_copies(values, axes, pad, grid.axes, space)
        self.rgi = RegularGridInterpolator(
            tuple(axes), values, method="linear", bounds_error=False, fill_value=np.nan
        )

    def __call__(self, x: FloatArray, nearest: np.ndarray) -> tuple[FloatArray, BoolArray]:
        out = np.asarray(self.rgi(x), dtype=np.float64)
        return out, np.asarray(np.isfinite(out).all(axis=1), dtype=np.bool_)


def _fill_copies(
    values: FloatArray,
    axes: list[FloatArray],
    pad: list[tuple[int, int]],
    nodes: tuple[FloatArray, ...],
    space: Space,
) -> None:
    """Give every padded node the value of the measured node it is a copy of."""
    shape = values.shape[:-1]
    inner = np.zeros(shape, dtype=np.bool_)
    inner[tuple(slice(lo, n - hi) for (lo, hi), n in zip(pad, shape, strict=True))] = True
    where = np.argwhere(~inner)
    if len(where) == 0:
        return
    points = np.stack([axes[k][where[:, k]] for k in range(len(axes))], axis=1)
    home = space.canonical(points)
    found = np.ones(len(home), dtype=np.bool_)
    source = []
    for k, a in enumerate(nodes):
        j = np.clip(np.searchsorted(a, home[:, k]), 1, len(a) - 1)
        j = np.where(np.abs(a[j - 1] - home[:, k]) <= np.abs(a[j] - home[:, k]), j - 1, j)
        found &= np.abs(a[j] - home[:, k]) <= NODE_TOLERANCE
        source.append(j + pad[k][0])
    src = tuple(np.asarray(s)[found] for s in source)
    values[tuple(where[found].T)] = values[src]


def refuse(parametrization: str) -> GonioError:
    """The one-line error for the ``grid`` method on samples that are not a grid."""
    return GonioError(
        f"method 'grid': the samples do not lie on a grid of {parametrization!r} "
        "coordinates (a plan with sampling.strategy: grid, reconstructed in its own "
        "parametrization); expected a grid plan, or use method 'linear' or 'rbf'"
    )
