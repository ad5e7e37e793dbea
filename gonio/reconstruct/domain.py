"""Where a reconstruction is supported by its measurement.

A query pair is supported when both directions are above the horizon, the rig can
measure it (`Rig.reachable`: within θmax, outside the blind spot, inside the footprint,
axis limits and clear of collisions; the rig's own rule, isotropic as the run was), a
measured sample (or a seam copy of one) lies close enough to it in the scaled
coordinate space, and the interpolant is defined there (inside the samples' hull; for
a grid, every corner of its cell measured). Elsewhere a value would be invented: the
reconstruction returns NaN unless asked to extrapolate.

Close enough: within `DISTANCE_FACTOR` times the *local* spacing of one of its
`SPACING_NEIGHBOURS` nearest samples — a sample's local spacing being the median, over
it and its `SPACING_NEIGHBOURS` − 1 nearest neighbours, of each one's distance to its
own nearest neighbour (scaled units). For a
uniform plan that is the plan's median spacing everywhere; for a plan denser in one
region (adaptive sampling) each region keeps its own, where one global median (the
dense region's) would leave the sparse regions unsupported. An explicit
``max_distance`` sets one distance for every sample instead.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.types import BoolArray, FloatArray

#: The default support distance in local nearest-neighbour spacings of the samples.
DISTANCE_FACTOR = 4.0
#: Samples whose nearest-neighbour distances give a sample's local spacing (itself
#: included).
SPACING_NEIGHBOURS = 8


class Domain:
    """The nearest-sample search and the rig's reachability of one reconstruction."""

    def __init__(
        self,
        points: FloatArray,
        source: np.ndarray,
        local: FloatArray,
        rig: Rig,
        isotropic: bool,
        max_distance: float | None = None,
    ) -> None:
        """``points``: the padded samples (scaled), ``source``: the measured sample each
        one copies; ``local``: each measured sample's local spacing (`spacings`)."""
        self.tree = cKDTree(points)
        self.rig = rig
        self.isotropic = isotropic
        if max_distance is None:
            reach = DISTANCE_FACTOR * local
        elif not max_distance > 0.0:
            raise GonioError(f"max_distance: expected a positive distance, got {max_distance}")
        else:
            reach = np.full(len(local), float(max_distance))
        #: The support distance around each padded point (its sample's).
        self.reach = np.asarray(reach[source], dtype=np.float64)
        #: The largest of them (the bound of every nearest-sample search).
        self.max_distance = float(self.reach.max()) if len(self.reach) else 0.0

    def nearest(self, x: FloatArray, *, bounded: bool = True) -> tuple[FloatArray, np.ndarray]:
        """Distance to and index of the nearest padded point, for scaled points (M, d);
        ``bounded``: only within ``max_distance`` (a faster search), beyond it the
        distance is inf and the index 0."""
        bound = self.max_distance if bounded else np.inf
        distance, index = self.tree.query(x, distance_upper_bound=bound, workers=-1)
        far = index >= self.tree.n
        return np.asarray(distance, dtype=np.float64), np.where(far, 0, index).astype(np.intp)

    def close(self, x: FloatArray, distance: FloatArray, nearest: np.ndarray) -> BoolArray:
        """The scaled points (M, d), at ``distance`` from their ``nearest`` padded point,
        lie within the support distance of one of their `SPACING_NEIGHBOURS` nearest
        padded points (the nearest one's, checked first, settles most)."""
        ok = np.asarray(distance <= self.reach[nearest], dtype=np.bool_)
        rest = np.flatnonzero(~ok & np.isfinite(distance))
        if len(rest):
            k = min(SPACING_NEIGHBOURS, self.tree.n)
            d, i = self.tree.query(x[rest], k=k, distance_upper_bound=self.max_distance, workers=-1)
            d = np.asarray(d, dtype=np.float64).reshape(len(rest), k)
            i = np.asarray(i, dtype=np.intp).reshape(len(rest), k)
            found = i < self.tree.n
            reach = np.where(found, self.reach[np.where(found, i, 0)], -1.0)
            ok[rest] = (d <= reach).any(axis=1)
        return ok

    def reachable(self, wi: FloatArray, wo: FloatArray) -> BoolArray:
        """The rig can measure the pairs (M, 3) (isotropic as the run was)."""
        if len(wi) == 0:
            return np.zeros(0, dtype=np.bool_)
        return np.asarray(self.rig.reachable(wi, wo, isotropic=self.isotropic)[0])


def spacings(samples: FloatArray) -> tuple[float, FloatArray]:
    """The median distance from a sample (N, d) to its nearest other sample, and each
    sample's local spacing (N,): that distance's median over it and its
    `SPACING_NEIGHBOURS` − 1 nearest samples (1.0 and ones for a lone sample); one
    nearest-neighbour search for both."""
    if len(samples) < 2:
        return 1.0, np.ones(len(samples))
    k = min(SPACING_NEIGHBOURS, len(samples))
    distance, around = cKDTree(samples).query(samples, k=k, workers=-1)
    own = np.asarray(distance, dtype=np.float64).reshape(len(samples), k)[:, 1]
    around = np.asarray(around, dtype=np.intp).reshape(len(samples), k)
    return float(np.median(own)), np.asarray(np.median(own[around], axis=1), dtype=np.float64)
