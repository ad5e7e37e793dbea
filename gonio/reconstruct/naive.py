"""The naive reference reconstruction: what a user would write in an afternoon, and the
floor every real method must beat (docs/explanations/evaluation.md).

1. The samples' coordinates in the run's parametrization (its isotropic reduction, three
   coordinates, for an isotropic run; four otherwise).
2. A regular grid of ``nodes`` points per axis over the parametrization's coordinate box
   (default: about one node per sample, ``round(N^(1/d))`` clipped to [2, 64]); the box's
   azimuth axes are treated as plain intervals (no wrap-around).
3. Each node takes the mean of ln(1 + f⁺) over the samples nearest to it (the samples in
   its cell); a node with none, inside the valid domain or not, takes the value of the
   nearest node that has some (`scipy.ndimage.distance_transform_edt`, in grid steps).
4. f(ωi, ωo) = exp(multilinear interpolation of that grid (`RegularGridInterpolator`)) − 1,
   the query's coordinates clipped to the box.

``supported(wi, wo)``: the query's nearest node holds at least one sample.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from scipy.ndimage import distance_transform_edt

from gonio import params
from gonio.analysis import Measured
from gonio.errors import GonioError
from gonio.types import BoolArray, FloatArray

#: The default nodes per axis are clipped to this range.
MIN_NODES, MAX_NODES = 2, 64


def default_nodes(samples: int, dims: int) -> int:
    """Nodes per axis for about one node per sample: round(samples^(1/dims)), clipped."""
    return int(np.clip(round(samples ** (1.0 / dims)), MIN_NODES, MAX_NODES))


class NaiveReconstruction:
    """The naive grid reconstruction of ``measured`` (see the module docstring), in
    ``parametrization`` (default: the run's) with ``nodes`` per axis (default:
    `default_nodes`). ``eval`` returns (...,) values in sr⁻¹, or (..., C) for RGB."""

    method = "naive"
    #: Outside the support (a node without samples): the nearest measured node's value.
    extrapolate = "nearest-node"

    def __init__(
        self,
        measured: Measured,
        *,
        parametrization: str | None = None,
        nodes: int | None = None,
    ) -> None:
        if len(measured) == 0:
            raise GonioError(f"{measured.source}: no sample to reconstruct from")
        self.parametrization = params.get(parametrization or measured.parametrization)
        self.isotropic = measured.isotropic
        p = self.parametrization
        self._bounds = np.asarray(p.iso_bounds if self.isotropic else p.bounds, dtype=np.float64)
        dims = len(self._bounds)
        self.nodes = nodes if nodes is not None else default_nodes(len(measured), dims)
        if self.nodes < MIN_NODES:
            raise ValueError(f"the grid needs at least {MIN_NODES} nodes per axis")
        self._shape = (self.nodes,) * dims
        axes = [np.linspace(lo, hi, self.nodes) for lo, hi in self._bounds]

        flat = self._node_of(measured.wi, measured.wo)
        cells = self.nodes**dims
        counts = np.bincount(flat, minlength=cells)
        values = np.log1p(np.maximum(np.asarray(measured.f, dtype=np.float64), 0.0))
        channels = values.reshape(len(values), -1).T
        sums = np.stack([np.bincount(flat, weights=v, minlength=cells) for v in channels], -1)
        self._filled = counts > 0
        mean = sums / np.maximum(counts, 1)[:, None]
        grid = mean.reshape(*self._shape, len(channels))
        if not self._filled.all():
            _, nearest = distance_transform_edt(
                ~self._filled.reshape(self._shape), return_indices=True
            )
            grid = grid[tuple(nearest)]
        if values.ndim == 1:
            grid = grid[..., 0]
        self._interpolator = RegularGridInterpolator(axes, grid, method="linear")

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
        """f(ωi, ωo) in sr⁻¹ for pairs (..., 3) (see the module docstring)."""
        lead = np.shape(wi)[:-1]
        coords = np.clip(self._coords(wi, wo), self._bounds[:, 0], self._bounds[:, 1])
        logf = self._interpolator(coords)
        f = np.maximum(np.expm1(logf), 0.0)
        return np.asarray(f.reshape(lead + f.shape[1:]), dtype=np.float64)

    def supported(self, wi: FloatArray, wo: FloatArray) -> BoolArray:
        """True where the pair's nearest grid node holds at least one sample."""
        lead = np.shape(wi)[:-1]
        return np.asarray(self._filled[self._node_of(wi, wo)].reshape(lead), dtype=np.bool_)

    def _coords(self, wi: FloatArray, wo: FloatArray) -> FloatArray:
        wi = np.asarray(wi, dtype=np.float64).reshape(-1, 3)
        wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
        p = self.parametrization
        return p.forward_iso(wi, wo) if self.isotropic else p.forward(wi, wo)

    def _node_of(self, wi: FloatArray, wo: FloatArray) -> np.ndarray:
        """The flat index of each pair's nearest grid node."""
        lo, hi = self._bounds[:, 0], self._bounds[:, 1]
        step = (hi - lo) / (self.nodes - 1)
        index = np.clip(np.rint((self._coords(wi, wo) - lo) / step), 0, self.nodes - 1)
        flat = np.ravel_multi_index(tuple(index.astype(np.intp).T), self._shape)
        return np.asarray(flat, dtype=np.intp)
