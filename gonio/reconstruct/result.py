"""`Reconstruction`: a measured BRDF one evaluates like an analytic model.

``eval(wi, wo)`` takes unit directions (..., 3) (sample frame, pointing away from the
surface, broadcast against each other) and returns f in sr⁻¹ of shape (...), plus a
trailing 3 for an RGB measurement; 0 where either direction is below the horizon, NaN
where the measurement does not support the pair (`supported` is False there) unless
the reconstruction extrapolates. ``uncertainty`` is the 1σ of ``eval`` (how it is
propagated: docs/explanations/reconstruction.md#uncertainty); NaN where a value is extrapolated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.blocks import blockwise
from gonio.directions import as_direction_pair
from gonio.reconstruct.coordinates import Space
from gonio.reconstruct.domain import Domain
from gonio.reconstruct.interpolants import Interpolant
from gonio.reconstruct.transforms import Transform
from gonio.types import ArrayLike, BoolArray, BrdfEval, Evaluable, FloatArray

#: Samples averaged by the nearest fill (`Reconstruction._nearby`).
FILL_NEIGHBOURS = 8
#: Pairs evaluated at once (`gonio.blocks.blockwise`): the cost per pair is flat from
#: a few thousand pairs to millions (each pair's value is its own: the same answer).
EVALUATION_BLOCK = 1 << 16


@dataclass(frozen=True)
class Reconstruction:
    """A BRDF reconstructed from N samples (see the module docstring).

    method, transform: how (`gonio.reconstruct.build.METHODS`, the transform's
    name); parametrization, isotropic: the coordinates interpolated in; extrapolate:
    None, "nearest" or "model"; channels: 1, or 3 for RGB.
    """

    method: str
    space: Space
    codec: Transform  # the transform itself (`transform` is its name)
    interpolant: Interpolant
    domain: Domain
    source: np.ndarray  # padded point → the measured sample it copies
    samples_f: FloatArray  # (N, C) measured values, for the "nearest" fill
    extrapolate: str | None
    model: BrdfEval | None
    channels: int
    seam_band: float  # scaled width over which the two sides of a seam are blended

    @property
    def parametrization(self) -> str:
        return self.space.parametrization

    @property
    def isotropic(self) -> bool:
        return self.space.isotropic

    @property
    def transform(self) -> str:
        return self.codec.name

    @property
    def is_rgb(self) -> bool:
        return self.channels == 3

    def eval(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """f(wi, wo) in sr⁻¹ (see the module docstring)."""
        return self.evaluate(wi, wo)[0]

    def uncertainty(self, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
        """The 1σ uncertainty of `eval` (sr⁻¹), same shape; 0 below the horizon."""
        return self.evaluate(wi, wo)[1]

    def supported(self, wi: ArrayLike, wo: ArrayLike) -> BoolArray:
        """True where the measurement supports the pair (docs/explanations/reconstruction.md)."""
        return self.evaluate(wi, wo)[2]

    def evaluate(self, wi: ArrayLike, wo: ArrayLike) -> tuple[FloatArray, FloatArray, BoolArray]:
        """(f, σ, supported) at once."""
        a, b = as_direction_pair(wi, wo)
        lead = a.shape[:-1]
        pairs = (a.reshape(-1, 3), b.reshape(-1, 3))
        f, sigma, ok = blockwise(self._block, *pairs, size=EVALUATION_BLOCK)
        shape = lead + ((3,) if self.is_rgb else ())
        return f.reshape(shape), sigma.reshape(shape), ok.reshape(lead)

    def _block(self, wi: FloatArray, wo: FloatArray) -> tuple[FloatArray, FloatArray, BoolArray]:
        """`evaluate` of pairs (M, 3): 0 (and unsupported) below the horizon."""
        rows = np.flatnonzero((wi[:, 2] >= 0.0) & (wo[:, 2] >= 0.0))
        if len(rows) == len(wi):
            return self._above(wi, wo)
        f = np.zeros((len(wi), self.channels))
        sigma = np.zeros_like(f)
        ok = np.zeros(len(wi), dtype=np.bool_)
        if len(rows):
            f[rows], sigma[rows], ok[rows] = self._above(wi[rows], wo[rows])
        return f, sigma, ok

    def _above(self, wi: FloatArray, wo: FloatArray) -> tuple[FloatArray, FloatArray, BoolArray]:
        x = self.space.scaled(wi, wo)
        distance, nearest = self.domain.nearest(x)
        near = np.flatnonzero(self.domain.close(x, distance, nearest))
        # In the order of their nearest sample (the samples follow a Z-order curve), so
        # that neighbouring queries read neighbouring simplices.
        near = near[np.argsort(nearest[near], kind="stable")]
        columns = np.full((len(x), 2 * self.channels), np.nan)
        ok = np.zeros(len(x), dtype=np.bool_)
        # (np.take and np.compress gather rows several times faster than indexing.)
        columns[near], ok[near] = self._blended(np.take(x, near, axis=0), nearest[near], 0)
        ok[ok] = self.domain.reachable(np.compress(ok, wi, axis=0), np.compress(ok, wo, axis=0))

        c = self.channels
        f = np.full((len(x), c), np.nan)
        sigma = np.full((len(x), c), np.nan)
        wi_ok, wo_ok = np.compress(ok, wi, axis=0), np.compress(ok, wo, axis=0)
        g = np.compress(ok, columns[:, :c], axis=0)
        f[ok] = self.codec.decode(g, wi_ok, wo_ok)
        sigma[ok] = self.codec.gain(g, wi_ok, wo_ok) * np.abs(
            np.compress(ok, columns[:, c:], axis=0)
        )
        out = ~ok
        if self.extrapolate == "nearest":
            f[out] = self._nearby(x[out])
        elif self.extrapolate == "model" and self.model is not None:
            m = np.asarray(self.model(wi[out], wo[out]), dtype=np.float64)
            f[out] = m[:, None] if m.ndim == 1 else m
        return f, sigma, ok

    def _nearby(self, x: FloatArray) -> FloatArray:
        """The fill of ``extrapolate="nearest"`` at scaled points (M, d): the mean of
        log(1 + f) over the `FILL_NEIGHBOURS` nearest samples weighted by 1/distance²
        (the nearest sample's value where a query sits on it)."""
        k = min(FILL_NEIGHBOURS, self.domain.tree.n)
        distance, index = self.domain.tree.query(x, k=k, workers=-1)
        distance = np.asarray(distance, dtype=np.float64).reshape(len(x), k)
        index = np.asarray(index, dtype=np.intp).reshape(len(x), k)
        weight = 1.0 / np.maximum(distance, 1e-12) ** 2
        weight /= weight.sum(axis=1, keepdims=True)
        g = np.log1p(np.maximum(self.samples_f[self.source[index]], 0.0))  # (M, k, C)
        return np.asarray(np.expm1(np.einsum("mk,mkc->mc", weight, g)), dtype=np.float64)

    def _blended(
        self, x: FloatArray, nearest: np.ndarray, level: int
    ) -> tuple[FloatArray, BoolArray]:
        """The interpolant, blended across each periodic seam (docs/explanations/reconstruction.md).

        Within `seam_band` of a seam, a query also has a representation one period
        away, inside the seam copies; the two interpolants there are built from
        different triangulations, so the result is their blend with weights going from
        ½ each at the seam to 1 for the query's own at the band's edge — the same
        value from both sides, continuous everywhere (a tensor-product blend when
        there are two periodic azimuths).
        """
        if level == len(self.space.periods):
            return self.interpolant(x, nearest)
        columns, defined = self._blended(x, nearest, level + 1)
        axis, period = self.space.periods[level]
        low = x[:, axis] < period / 2
        gap = np.where(low, x[:, axis], period - x[:, axis])
        rows = np.flatnonzero(gap < self.seam_band)
        if len(rows) == 0:
            return columns, defined
        other = x[rows].copy()
        other[:, axis] += np.where(low[rows], period, -period)
        distance, near_other = self.domain.nearest(other)
        close = self.domain.close(other, distance, near_other)
        other_columns = np.full((len(rows), columns.shape[1]), np.nan)
        other_defined = np.zeros(len(rows), dtype=np.bool_)
        other_columns[close], other_defined[close] = self._blended(
            other[close], near_other[close], level + 1
        )
        # Where the copy falls outside the samples' hull (at its edge), the query's own
        # value stands alone.
        w = np.where(other_defined, 0.5 * (1.0 - gap[rows] / self.seam_band), 0.0)
        other_columns[~other_defined] = 0.0
        columns[rows] = (1.0 - w[:, None]) * columns[rows] + w[:, None] * other_columns
        return columns, defined


def values_and_support(
    surface: Evaluable, wi: FloatArray, wo: FloatArray
) -> tuple[FloatArray, BoolArray | None]:
    """f at the pairs and where ``surface`` has data (None when it does not say), at
    once: a `Reconstruction`'s ``eval`` and ``supported`` each run its whole evaluation,
    so it is evaluated once; anything else by its ``eval`` and ``supported``."""
    if isinstance(surface, Reconstruction):
        f, _, ok = surface.evaluate(wi, wo)
        return f, ok
    supported = getattr(surface, "supported", None)
    mask = None if supported is None else np.asarray(supported(wi, wo), dtype=np.bool_)
    return np.asarray(surface.eval(wi, wo), dtype=np.float64), mask
