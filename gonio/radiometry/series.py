"""The inversion of a run's readings through a series of reference readings over run
time (docs/explanations/acquisition.md#calibration): counts → BRDF with the source's
drift divided out, and its 1σ uncertainty.

Every calibration holds a reading of the reference standard (albedo ρ, at the
rig's calibration geometry) and a dark reading, both at one exposure e_ref with
``averages`` exposures each. With d(t) the dark rate (counts/s) and S(t) the
dark-subtracted reference rate, each interpolated linearly in run time between the
calibrations (constant beyond the first and the last), a sample of mean counts C over
exposure e at run time t (the middle of its exposures) and pair (ωi, ωo) gives

    s = C/e − d(t),    f = (ρ/π) · (s / S(t)) · (g_ref / g(ωi, ωo))

with g the geometric factor of the source kind (`gonio.radiometry.calibration`): the
source's drift cancels in s/S(t). Uncertainty (1σ): the variance of C is the sample's
own spread std²/n when it averaged n ≥ 2 exposures, else the calibration's noise model
var(C) = a + b·max(C − d·e, 0) per exposure, with a the dark reading's variance and b
the reference's excess variance per count (counting statistics: shot noise grows with
the signal, read and dark noise do not); the reference and dark rates carry the
variance of their means. These add in quadrature through the formula above. A detector
that averages on its own and reports no spread gives no noise estimate: its readings
count as exact there (docs/explanations/acquisition.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.radiometry.calibration import relative_geometry
from gonio.types import FloatArray


@dataclass(frozen=True)
class CalibrationSeries:
    """The calibration readings of a run, in run time (see the module docstring)."""

    albedo: float
    source_kind: str
    wi: FloatArray  # (3,) of the first reference reading
    wo: FloatArray
    t: FloatArray  # (K,) middle of each reference reading (s)
    dark_rate: FloatArray  # (K,) counts/s
    dark_rate_var: FloatArray  # (K,) (counts/s)² of the mean
    rate: FloatArray  # (K,) dark-subtracted reference rate, counts/s
    rate_var: FloatArray  # (K,)
    noise_a: float  # counts² per exposure (dark)
    noise_b: float  # counts² per count of signal

    def _at(self, values: FloatArray, t: FloatArray) -> FloatArray:
        return np.asarray(np.interp(t, self.t, values), dtype=np.float64)

    def _var_at(self, var: FloatArray, t: FloatArray) -> FloatArray:
        """Variance of the linear interpolation of independent readings."""
        if len(self.t) == 1:
            return np.full(np.shape(t), float(var[0]))
        j = np.clip(np.searchsorted(self.t, t) - 1, 0, len(self.t) - 2)
        t0, t1 = self.t[j], self.t[j + 1]
        w = np.clip((t - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0, 1.0)
        return np.asarray((1 - w) ** 2 * var[j] + w**2 * var[j + 1], dtype=np.float64)

    def brdf(
        self,
        counts: FloatArray,
        std: FloatArray,
        n: np.ndarray,
        exposure_s: FloatArray,
        wi: FloatArray,
        wo: FloatArray,
        t: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """(f, σ_f) of samples (see the module docstring); arrays (N,), pairs (N, 3)."""
        d = self._at(self.dark_rate, t)
        s = counts / exposure_s - d
        big_s = self._at(self.rate, t)
        g_ref = float(relative_geometry(self.source_kind, self.wi, self.wo))  # type: ignore[arg-type]
        g = relative_geometry(self.source_kind, wi, wo)  # type: ignore[arg-type]
        scale = self.albedo / math.pi * g_ref / np.where(g > 0, g, 1.0)
        f = scale * s / big_s
        modelled = self.noise_a + self.noise_b * np.maximum(counts - d * exposure_s, 0.0)
        own = (n >= 2) & np.isfinite(std)
        var_counts = np.where(own, std**2 / np.maximum(n, 1), modelled / np.maximum(n, 1))
        var_s = var_counts / exposure_s**2 + self._var_at(self.dark_rate_var, t)
        var_big = self._var_at(self.rate_var, t)
        sigma = scale * np.sqrt(var_s / big_s**2 + s**2 * var_big / big_s**4)
        return np.asarray(f, dtype=np.float64), np.asarray(sigma, dtype=np.float64)
