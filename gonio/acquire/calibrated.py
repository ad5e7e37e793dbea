"""BRDF values and their uncertainty from a journaled run's raw counts, through its
calibration readings (docs/acquire.md#calibration).

Every calibration event holds a reading of the reference standard (albedo ρ, at the
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
count as exact there (docs/acquire.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError
from gonio.radiometry.calibration import relative_geometry
from gonio.store.read import Event, Run
from gonio.types import FloatArray


@dataclass(frozen=True)
class Calibrated:
    """Per sample (in the run's sample order): f (sr⁻¹) and its 1σ uncertainty."""

    brdf: FloatArray
    sigma: FloatArray
    series: CalibrationSeries


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

    @classmethod
    def from_events(cls, events: tuple[Event, ...]) -> CalibrationSeries:
        if not events:
            raise GonioError("the run has no calibration reading: no BRDF can be derived")
        t, dark, dark_var, ref, ref_var, a_s, b_s = [], [], [], [], [], [], []
        for e in events:
            r, d = e.data["reference"], e.data["dark"]
            exposure = float(r["exposure_s"])
            n = max(int(r["n"]), 1)
            t.append(0.5 * (float(r["started_s"]) + float(r["ended_s"])))
            if d is None:
                dark_counts, dark_std, dn = 0.0, 0.0, 1
            else:
                dark_counts, dark_std, dn = float(d["value"]), _std(d), max(int(d["n"]), 1)
            dark.append(dark_counts / exposure)
            dark_var.append(dark_std**2 / dn / exposure**2)
            signal = float(r["value"]) - dark_counts
            ref.append(signal / exposure)
            ref_var.append((_std(r) ** 2 / n + dark_std**2 / dn) / exposure**2)
            a_s.append(dark_std**2)
            b_s.append(max(_std(r) ** 2 - dark_std**2, 0.0) / max(signal, 1e-300))
        first = events[0].data
        rate = np.array(ref)
        if np.any(rate <= 0):
            raise GonioError("a reference reading is not above its dark reading: no calibration")
        return cls(
            albedo=float(first["albedo"]),
            source_kind=str(first["source_kind"]),
            wi=np.array(first["wi"], dtype=np.float64),
            wo=np.array(first["wo"], dtype=np.float64),
            t=np.array(t),
            dark_rate=np.array(dark),
            dark_rate_var=np.array(dark_var),
            rate=rate,
            rate_var=np.array(ref_var),
            noise_a=float(np.mean(a_s)),
            noise_b=float(np.mean(b_s)),
        )

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


def _std(reading: dict[str, object]) -> float:
    """A journaled reading's spread (counts); 0 where the device gave none."""
    std = reading.get("std")
    return 0.0 if std is None else float(std)  # type: ignore[arg-type]


def calibrate(run: Run) -> Calibrated:
    """The run's BRDF values and uncertainties (`GonioError` without a calibration)."""
    series = CalibrationSeries.from_events(run.of_kind("calibration"))
    s = run.samples
    wi, wo = run.directions()
    t = 0.5 * (s["started_s"] + s["ended_s"])
    f, sigma = series.brdf(s["counts"], s["counts_std"], s["n"], s["exposure_s"], wi, wo, t)
    return Calibrated(f, sigma, series)
