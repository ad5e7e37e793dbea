"""Where a reconstruction is supported by its measurement.

A query pair is supported when both directions are above the horizon, the rig can
measure it (`Rig.reachable`: within θmax, outside the blind spot, inside the footprint,
axis limits and clear of collisions; the rig's own rule, isotropic as the run was), a
measured sample (or a seam copy of one) lies within ``max_distance`` of it in the
scaled coordinate space, and the interpolant is defined there (inside the samples'
hull; for a grid, every corner of its cell measured). Elsewhere a value would be
invented: the reconstruction returns NaN unless asked to extrapolate.

``max_distance`` defaults to `DISTANCE_FACTOR` times the median distance from a
sample to its nearest neighbour (scaled units), which follows the plan's density.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from gonio.errors import GonioError
from gonio.rig.model import Rig
from gonio.types import BoolArray, FloatArray

#: The default ``max_distance`` in median nearest-neighbour distances of the samples.
DISTANCE_FACTOR = 4.0


class Domain:
    """The nearest-sample search and the rig's reachability of one reconstruction."""

    def __init__(
        self,
        points: FloatArray,
        samples: FloatArray,
        rig: Rig,
        isotropic: bool,
        max_distance: float | None = None,
    ) -> None:
        """``points``: the padded samples (scaled); ``samples``: the measured ones."""
        self.tree = cKDTree(points)
        self.rig = rig
        self.isotropic = isotropic
        if max_distance is None:
            max_distance = DISTANCE_FACTOR * typical_spacing(samples)
        elif not max_distance > 0.0:
            raise GonioError(f"max_distance: expected a positive distance, got {max_distance}")
        self.max_distance = float(max_distance)

    def nearest(self, x: FloatArray, *, bounded: bool = True) -> tuple[FloatArray, np.ndarray]:
        """Distance to and index of the nearest padded point, for scaled points (M, d);
        ``bounded``: only within ``max_distance`` (a faster search), beyond it the
        distance is inf and the index 0."""
        bound = self.max_distance if bounded else np.inf
        distance, index = self.tree.query(x, distance_upper_bound=bound, workers=-1)
        far = index >= self.tree.n
        return np.asarray(distance, dtype=np.float64), np.where(far, 0, index).astype(np.intp)

    def reachable(self, wi: FloatArray, wo: FloatArray) -> BoolArray:
        """The rig can measure the pairs (M, 3) (isotropic as the run was)."""
        if len(wi) == 0:
            return np.zeros(0, dtype=np.bool_)
        return np.asarray(self.rig.reachable(wi, wo, isotropic=self.isotropic)[0])


def typical_spacing(samples: FloatArray) -> float:
    """The median distance from a sample (N, d) to its nearest other sample."""
    if len(samples) < 2:
        return 1.0
    distance, _ = cKDTree(samples).query(samples, k=2)
    return float(np.median(distance[:, 1]))
