"""Direction-pair geometry the models share: coercion, cosines, halfway vector.

Every quantity here is computed from Cartesian components without inverse
trigonometry, and stays finite for any pair of unit vectors, including grazing
(z = 0), wi = wo and wi = −wo. Angles follow the usual names: θi, θo (to the
normal), θh (normal to halfway vector), θd (wi to halfway vector), ψ (mirror
direction of wi to wo).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.directions import as_direction_pair
from gonio.types import ArrayLike, BoolArray, FloatArray


@dataclass(frozen=True)
class Pair:
    """Components of a broadcast pair of directions, each of shape ``shape``.

    ``ci``, ``co`` are cos θi, cos θo clamped to [0, 1] (safe in denominators and
    square roots); ``above`` is True where both directions have z ≥ 0.
    """

    xi: FloatArray
    yi: FloatArray
    zi: FloatArray
    xo: FloatArray
    yo: FloatArray
    zo: FloatArray
    ci: FloatArray
    co: FloatArray
    above: BoolArray

    @property
    def shape(self) -> tuple[int, ...]:
        return self.zi.shape

    def dot(self) -> FloatArray:
        """wi · wo."""
        return self.xi * self.xo + self.yi * self.yo + self.zi * self.zo

    def halfway(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The direction of wi + wo, rescaled so its largest component is ±1 (or 0).

        Only the direction is meaningful; the scale keeps ratios of its components
        free of underflow when wi ≈ −wo. At wi = −wo exactly all three are 0.
        """
        hx, hy, hz = self.xi + self.xo, self.yi + self.yo, self.zi + self.zo
        m = np.maximum(np.maximum(np.abs(hx), np.abs(hy)), np.abs(hz))
        m = np.where(m > 0.0, m, 1.0)  # dividing (not multiplying by 1/m) cannot overflow
        return hx / m, hy / m, hz / m

    def cos_theta_h(self) -> FloatArray:
        """cos θh = ĥ · n, with ĥ the unit halfway vector (0 where wi = −wo)."""
        hx, hy, hz = self.halfway()
        norm = np.sqrt(hx * hx + hy * hy + hz * hz)
        return np.asarray(hz / np.where(norm > 0.0, norm, 1.0), dtype=np.float64)

    def cos_theta_d(self) -> FloatArray:
        """cos θd = wi · ĥ = ‖wi + wo‖ / 2 for unit vectors, in [0, 1]."""
        hx, hy, hz = self.xi + self.xo, self.yi + self.yo, self.zi + self.zo
        return np.minimum(0.5 * np.sqrt(hx * hx + hy * hy + hz * hz), 1.0)

    def cos_psi(self) -> FloatArray:
        """cos ψ = r · wo with r = 2 (wi · n) n − wi the mirror direction of wi.

        Equal to 2 cos θi cos θo − wi · wo, symmetric in wi and wo.
        """
        return np.clip(2.0 * self.zi * self.zo - self.dot(), -1.0, 1.0)


def pair(wi: ArrayLike, wo: ArrayLike) -> Pair:
    """The `Pair` of two direction arrays (see `gonio.directions.as_direction_pair`)."""
    a, b = as_direction_pair(wi, wo)
    xi, yi, zi = (np.array(a[..., j], dtype=np.float64) for j in range(3))
    xo, yo, zo = (np.array(b[..., j], dtype=np.float64) for j in range(3))
    return Pair(
        xi=xi,
        yi=yi,
        zi=zi,
        xo=xo,
        yo=yo,
        zo=zo,
        ci=np.clip(zi, 0.0, 1.0),
        co=np.clip(zo, 0.0, 1.0),
        above=(zi >= 0.0) & (zo >= 0.0),
    )
