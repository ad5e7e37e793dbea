"""Bilinear densities on the unit square that depend on parameters, and their
marginal-conditional warp (the interpolant of Dupuy & Jakob 2018's RGL materials, as
docs/reference/formats.md#rgl describes it); numpy, float64, vectorized over queries.

A table of shape ``(P1, …, Pk, H, W)`` holds, for each node of the parameters, the
values of a function at the ``H × W`` nodes ``(x, y) = (j/(W−1), i/(H−1))`` of the unit
square (``x`` along the last axis). Between nodes the function is bilinear; between
parameter nodes every looked-up quantity (value, or the warp's cumulative sums) is
linear in each parameter, clamped at the outermost nodes; a parameter with one node is
constant.

The warp (`Marginal2D`) normalizes each slice to integrate to 1 over the square, then
maps a uniform sample ``s`` to a point ``u`` distributed as the density: ``u``'s row
coordinate by the marginal (the integral of each row, linear between rows), its column
by the conditional along the row interpolated at ``u``'s row coordinate; `invert` is
the exact inverse of `sample` for a given parameter.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from gonio.types import FloatArray


class Table:
    """``values`` ``(P1, …, Pk, H, W)`` at parameter nodes ``params`` (k increasing
    arrays), interpolated as the module docstring says (`eval`)."""

    def __init__(self, values: ArrayLike, params: tuple[ArrayLike, ...] = ()) -> None:
        values = np.asarray(values, dtype=np.float64)
        self.params = tuple(np.asarray(p, dtype=np.float64) for p in params)
        self.shape = values.shape[-2:]
        sizes = [len(p) for p in self.params]
        if list(values.shape[:-2]) != sizes or min(self.shape) < 2:
            raise ValueError(f"table {values.shape} does not match parameters {sizes}")
        # Strides of each parameter over the flattened slices (0 for a single node).
        strides = np.cumprod([1, *sizes[::-1]])[:-1][::-1] if sizes else np.zeros(0, int)
        self.strides = [int(s) if n > 1 else 0 for s, n in zip(strides, sizes, strict=True)]
        self.data = values.reshape(-1, self.shape[0] * self.shape[1])

    def corners(
        self, param: tuple[FloatArray, ...], n: tuple[int, ...]
    ) -> tuple[np.ndarray, FloatArray]:
        """Slice indices and weights (..., 2**k) of the parameter values (each of shape
        ``n``)."""
        index = np.zeros((*n, 1), dtype=np.int64)
        weight = np.ones((*n, 1))
        for nodes, stride, p in zip(self.params, self.strides, param, strict=True):
            if len(nodes) == 1:
                continue
            i0 = np.clip(np.searchsorted(nodes, p, side="left") - 1, 0, len(nodes) - 2)
            w1 = np.clip((p - nodes[i0]) / (nodes[i0 + 1] - nodes[i0]), 0.0, 1.0)
            low, high = (i0 * stride)[..., None], ((i0 + 1) * stride)[..., None]
            index = np.concatenate([index + low, index + high], axis=-1)
            weight = np.concatenate([weight * (1 - w1)[..., None], weight * w1[..., None]], -1)
        return index, weight

    @staticmethod
    def lookup(
        table: FloatArray, slices: np.ndarray, weights: FloatArray, at: np.ndarray
    ) -> FloatArray:
        """Σ weight · table[slice, at] over the corners: ``at`` (N,) within a slice."""
        return np.asarray(np.sum(weights * table[slices, at[..., None]], axis=-1))

    def _cell(self, u: FloatArray) -> tuple[np.ndarray, np.ndarray, FloatArray, FloatArray]:
        """Lower node (col, row) of ``u``'s cell and the fractions within it."""
        h, w = self.shape
        gx = np.clip(u[..., 0], 0.0, 1.0) * (w - 1)
        gy = np.clip(u[..., 1], 0.0, 1.0) * (h - 1)
        col = np.minimum(gx.astype(np.int64), w - 2)
        row = np.minimum(gy.astype(np.int64), h - 2)
        return col, row, gx - col, gy - row

    def eval(self, u: FloatArray, param: tuple[FloatArray, ...] = ()) -> FloatArray:
        """The bilinear value at points ``u`` (..., 2) of the square (x, y) for
        parameters ``param`` (each broadcast to u's leading shape)."""
        u, param = _broadcast(u, param)
        slices, weights = self.corners(param, u.shape[:-1])
        col, row, fx, fy = self._cell(u)
        w = self.shape[1]
        at = row * w + col

        def v(offset: int) -> FloatArray:
            return self.lookup(self.data, slices, weights, at + offset)

        c0 = v(0) * (1 - fy) + v(w) * fy
        c1 = v(1) * (1 - fy) + v(w + 1) * fy
        return np.asarray(c0 * (1 - fx) + c1 * fx)


class Marginal2D(Table):
    """A `Table` of non-negative values, normalized slice by slice, with its warp
    (`sample`, `invert`): see the module docstring."""

    def __init__(self, values: ArrayLike, params: tuple[ArrayLike, ...] = ()) -> None:
        super().__init__(values, params)
        h, w = self.shape
        grid = self.data.reshape(-1, h, w)
        # Conditional: along each row, the integral from x = 0 to each node (trapezoids).
        cond = np.zeros_like(grid)
        cond[..., 1:] = np.cumsum(0.5 * (grid[..., 1:] + grid[..., :-1]), axis=-1) / (w - 1)
        rows = cond[..., -1]
        marg = np.zeros(rows.shape)
        marg[:, 1:] = np.cumsum(0.5 * (rows[:, 1:] + rows[:, :-1]), axis=-1) / (h - 1)
        total = marg[:, -1:]
        if np.any(~(total > 0)):
            raise ValueError("a slice of the density integrates to 0")
        self.data = (grid / total[..., None]).reshape(len(grid), -1)
        self.cond = (cond / total[..., None]).reshape(len(grid), -1)
        self.marg = marg / total

    def invert(self, u: FloatArray, param: tuple[FloatArray, ...] = ()) -> FloatArray:
        """The uniform sample (..., 2) that `sample` maps to ``u`` (..., 2)."""
        u, param = _broadcast(u, param)
        slices, weights = self.corners(param, u.shape[:-1])
        h, w = self.shape
        col, row, fx, fy = self._cell(u)
        at = row * w + col

        def get(table: FloatArray, index: np.ndarray) -> FloatArray:
            return self.lookup(table, slices, weights, index)

        c0 = get(self.data, at) * (1 - fy) + get(self.data, at + w) * fy
        c1 = get(self.data, at + 1) * (1 - fy) + get(self.data, at + w + 1) * fy
        # Mass of the row-interpolated density from x = 0 to u's x.
        before = get(self.cond, at) * (1 - fy) + get(self.cond, at + w) * fy
        x = before + fx * (c0 + 0.5 * fx * (c1 - c0)) / (w - 1)
        r0 = get(self.cond, row * w + w - 1)
        r1 = get(self.cond, row * w + 2 * w - 1)
        x = x / (r0 * (1 - fy) + r1 * fy)
        y = get(self.marg, row) + fy * (r0 + 0.5 * fy * (r1 - r0)) / (h - 1)
        return np.stack([x, y], axis=-1)

    def sample(self, s: FloatArray, param: tuple[FloatArray, ...] = ()) -> FloatArray:
        """The point (..., 2) of the square a uniform sample ``s`` (..., 2) maps to."""
        s, param = _broadcast(np.clip(np.asarray(s, dtype=np.float64), 0.0, 1.0), param)
        slices, weights = self.corners(param, s.shape[:-1])
        h, w = self.shape
        # The marginal at every row node, interpolated in the parameters: (..., H).
        marg = np.einsum("...c,...ch->...h", weights, self.marg[slices])
        row = np.clip(np.sum(marg[..., 1:-1] < s[..., 1:2], axis=-1), 0, h - 2)
        cond = self._rows(slices, weights, row)
        r0, r1 = cond[..., 0, -1], cond[..., 1, -1]
        rest = s[..., 1] - np.take_along_axis(marg, row[..., None], -1)[..., 0]
        fy = _segment(rest * (h - 1), r0, r1)
        line = cond[..., 0, :] * (1 - fy[..., None]) + cond[..., 1, :] * fy[..., None]
        target = s[..., 0] * line[..., -1]
        col = np.clip(np.sum(line[..., 1:-1] < target[..., None], axis=-1), 0, w - 2)
        rest = target - np.take_along_axis(line, col[..., None], -1)[..., 0]
        at = row * w + col

        def v(offset: int) -> FloatArray:
            return self.lookup(self.data, slices, weights, at + offset)

        c0 = v(0) * (1 - fy) + v(w) * fy
        c1 = v(1) * (1 - fy) + v(w + 1) * fy
        fx = _segment(rest * (w - 1), c0, c1)
        return np.stack([(col + fx) / (w - 1), (row + fy) / (h - 1)], axis=-1)

    def _rows(self, slices: np.ndarray, weights: FloatArray, row: np.ndarray) -> FloatArray:
        """The conditional sums of rows ``row`` and ``row + 1`` (..., 2, W), interpolated."""
        h, w = self.shape
        cond = self.cond.reshape(-1, h, w)
        pair = np.stack([row, row + 1], axis=-1)  # (..., 2)
        picked = cond[slices[..., None, :], pair[..., :, None]]  # (..., 2, C, W)
        return np.asarray(np.einsum("...c,...rcx->...rx", weights, picked))


def _segment(mass: FloatArray, v0: FloatArray, v1: FloatArray) -> FloatArray:
    """t in [0, 1] with ∫₀ᵗ (v0 + (v1 − v0)τ) dτ = ``mass`` (a linear density on a unit
    cell), in the form stable when v0 ≈ v1."""
    root = np.sqrt(np.maximum(v0 * v0 + 2.0 * (v1 - v0) * mass, 0.0))
    denominator = v0 + root
    safe = np.where(denominator > 0, denominator, 1.0)
    return np.clip(np.where(denominator > 0, 2.0 * mass / safe, 0.0), 0.0, 1.0)


def _broadcast(
    u: FloatArray, param: tuple[FloatArray, ...]
) -> tuple[FloatArray, tuple[FloatArray, ...]]:
    """Points (..., 2) and parameters broadcast to one leading shape, as float64."""
    u = np.asarray(u, dtype=np.float64)
    ps = tuple(np.asarray(p, dtype=np.float64) for p in param)
    lead = np.broadcast_shapes(u.shape[:-1], *(p.shape for p in ps))
    return np.broadcast_to(u, (*lead, 2)), tuple(np.broadcast_to(p, lead) for p in ps)
