"""The inversion of a run's readings through a series of reference readings over run
time (docs/explanations/acquisition.md#calibration): counts → BRDF with the source's
drift divided out, and its 1σ uncertainty.

Every calibration holds a reading of the reference standard (albedo ρ, at the rig's
calibration geometry) and a dark reading, both at one exposure e_ref with ``averages``
exposures each. With d(t) the dark rate (counts/s) and S(t) the dark-subtracted
reference rate, interpolated in run time between the calibrations
(`CalibrationSeries.weights`: S(t) by a not-a-knot cubic spline through three or more
readings, d(t), and S(t) through two, by a line; each constant beyond the first and the
last), a sample of mean counts C over exposure e at run time t (the middle of its
exposures) and pair (ωi, ωo) gives

    s = C/e − d(t),    f = (ρ/π) · (s / S(t)) · (g_ref / g(ωi, ωo))

with g the geometric factor of the source kind (`gonio.radiometry.calibration`): the
source's drift cancels in s/S(t). The interpolation is linear in the readings (S(t) =
Σ_k w_k(t) S_k), so its noise follows from the weights. A spline follows a drift that
bends between calibrations (a lamp's slow oscillation), which a straight line cuts
through: the line's error, −S''·(t − t_k)(t_k+1 − t)/2, averages −S''Δ²/12 over an
interval Δ and keeps its sign over half a period of the drift, so it adds up over a run
instead of averaging out (`studies/calibration.py` measures both).

Uncertainty (1σ): the variance of C is the sample's own spread std²/n when it averaged
n ≥ 2 exposures, else the calibration's noise model var(C) = a + b·max(C − d·e, 0) per
exposure, with a the dark readings' variance and b the reference's excess variance per
count (counting statistics: shot noise grows with the signal, read and dark noise do
not). The reference and dark rates carry the variance of their means, (a + b·signal)/n
and a/n, from the same model pooled over the K calibrations. That model is itself
estimated, from the readings' spreads: from ν = Σ_k (n_k − 1) degrees of freedom (the
references', and the darks' for a), so an error divided by its σ follows Student's t
with ν degrees of freedom, whose variance is ν/(ν − 2), not 1 (3 calibrations of 4
exposures: ν = 9, a spread of √(9/7) = 1.13; the scale's z-scores spread 1.18). The
model's two points, a at no signal and a + b·S̄ at the references' mean signal S̄, are
each multiplied by that factor of their own ν (`student_variance`: the standard
uncertainty of a t-distributed quantity, JCGM 101:2008 6.4.9.4), so the z-scores of
every value derived from the model have unit variance at every exposure count; with
ν ≤ 2 a t has no finite variance and no σ is given (the plan asks for at least 4
exposures a reading, ν ≥ 3 from one calibration). These add in quadrature through the
formula above. One error is not reduced by averaging: a dark reading in ADC codes whose
noise is below a code is rounded the same way in every exposure and every calibration
(`rounding_var`); it enters s and S(t) alike, so f carries it as (s − S)/(S s) times the
dark rate's error. A detector that averages on its own and reports no spread gives no
noise estimate: its readings count as exact there (docs/explanations/acquisition.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicSpline

from gonio.radiometry.calibration import relative_geometry
from gonio.types import ArrayLike, FloatArray

#: The largest variance gain Σ_k w_k(t)² of the reference rate's interpolation the
#: spline may have (a regular schedule's is at most 1.4, 2.3 with its intervals ±20 %
#: apart; a calibration a second after another: hundreds); beyond it, the line's (≤ 1).
NOISE_GAIN = 3.0

#: Matrix entries (samples × calibrations) `CalibrationSeries.brdf` holds at once: a run
#: of 10⁶ samples and 10³ calibrations is computed in blocks of 4 000 samples, 32 MB each.
BLOCK_ENTRIES = 1 << 22

#: Terms of `rounding_var`'s series (its truncation error is below 3e-4 relative).
_ROUNDING_TERMS = 2000


def _spline_weights(
    knots: FloatArray, t: FloatArray, spline: CubicSpline | None = None
) -> FloatArray:
    """(N, K) weights of the not-a-knot cubic spline through K ≥ 3 increasing ``knots``
    at ``t`` (inside them): the spline of each unit vector (Lagrange's parabola for 3,
    which that spline is); ``spline``: that spline of the unit vectors (`_unit_spline`), when
    the caller has it."""
    if len(knots) == 3:
        x = knots
        basis = [
            (t - x[(j + 1) % 3])
            * (t - x[(j + 2) % 3])
            / ((x[j] - x[(j + 1) % 3]) * (x[j] - x[(j + 2) % 3]))
            for j in range(3)
        ]
        return np.asarray(np.stack(basis, axis=-1), dtype=np.float64)
    if spline is None:
        spline = _unit_spline(knots)
    return np.asarray(spline(t), dtype=np.float64)


def _unit_spline(knots: FloatArray) -> CubicSpline:
    """The not-a-knot cubic spline of the K unit vectors through K > 3 ``knots``."""
    return CubicSpline(knots, np.eye(len(knots)), bc_type="not-a-knot")


def rounding_var(noise: ArrayLike) -> FloatArray:
    """Mean square (codes²) of the error rounding to whole ADC codes leaves in the mean
    of many readings of one level x whose noise is Gaussian of σ = ``noise`` (codes),
    over where x lies within its code.

    Averaging removes the rounding error only where the noise dithers it: the mean of
    round(x + n) tends to E[round(x + n)] = x + β(x), with β the sawtooth
    round(x) − x = Σ_m (−1)^m sin(2πmx)/(πm) smoothed by the noise (each harmonic
    times the noise's characteristic function e^(−2π²m²σ²)). Over x uniform in a code,
    E[β²] = Σ_m≥1 e^(−4π²m²σ²)/(2π²m²): the resolution term 1/12 at σ = 0, 0.015 at
    σ = 0.175, below 1e-8 from σ = 0.5 on. β is the same for every reading of the same
    level: an error shared by all of them, not reduced by more exposures or readings."""
    sigma = np.asarray(noise, dtype=np.float64)
    m = np.arange(1, _ROUNDING_TERMS + 1, dtype=np.float64)
    terms = np.exp(-4.0 * math.pi**2 * np.multiply.outer(sigma**2, m**2)) / (
        2.0 * math.pi**2 * m**2
    )
    return np.asarray(terms.sum(axis=-1), dtype=np.float64)


def student_variance(dof: float) -> float:
    """ν/(ν − 2): the variance of Student's t with ``dof`` = ν degrees of freedom, the
    factor by which a variance estimated from ν degrees of freedom is multiplied so that
    an error divided by its square root has unit variance (JCGM 101:2008 6.4.9.4: the
    standard uncertainty of a quantity whose spread is estimated from n readings, ν =
    n − 1); 1 for ν = ∞ (a known variance), ∞ for ν ≤ 2 (no finite variance)."""
    if dof <= 2:
        return math.inf
    return 1.0 if math.isinf(dof) else dof / (dof - 2.0)


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
    noise_a: float  # counts² per exposure (dark), times its `student_variance`
    noise_b: float  # counts² per count of signal, as expanded (module docstring)
    #: (K,) counts/s: 1σ of the error the ADC's rounding leaves in each dark rate
    #: (`rounding_var`), the same error in every reading (fully correlated); 0: none.
    dark_rounding: FloatArray | None = None
    #: Degrees of freedom of the reference readings' noise estimate (∞: none estimated).
    noise_dof: float = math.inf

    def weights(self, t: ArrayLike, *, spline: bool = True) -> FloatArray:
        """(N, K): the interpolated rate at run times ``t`` (s, (N,)) as a combination
        of the K readings (rows sum to 1): a not-a-knot cubic spline through K ≥ 3
        readings (a parabola for 3), a line through 2 (and where the spline would
        amplify the readings' noise, `NOISE_GAIN`; and without ``spline``: the dark
        rate's, which does not follow the source), constant beyond the first and the
        last reading (see the module)."""
        t = np.clip(np.asarray(t, dtype=np.float64), self.t[0], self.t[-1])
        k = len(self.t)
        if k == 1:
            return np.ones((*t.shape, 1))
        if spline and k >= 3 and self._spline_holds:
            return _spline_weights(self.t, t, self._basis)
        eye = np.eye(k)
        columns = [np.interp(t, self.t, eye[j]) for j in range(k)]
        return np.asarray(np.stack(columns, axis=-1), dtype=np.float64)

    def dark_at(self, t: ArrayLike) -> FloatArray:
        """d(t): the dark rate (counts/s) at run times ``t`` (s), linear between the
        readings (the dark current does not follow the source's drift; a spline would
        only pass the readings' noise on)."""
        return np.asarray(self.weights(t, spline=False) @ self.dark_rate, dtype=np.float64)

    @cached_property
    def _spline_holds(self) -> bool:
        """Whether the spline's variance gain Σ_k w_k(t)² stays within `NOISE_GAIN`
        (the line's is at most 1): not where one calibration follows another within a
        fraction of the others' spacing."""
        if np.any(np.diff(self.t) <= 0):
            return False
        fractions = np.linspace(0.0, 1.0, 9)[1:-1]
        probe = (self.t[:-1, None] + np.diff(self.t)[:, None] * fractions).ravel()
        gain = np.sum(_spline_weights(self.t, probe, self._basis) ** 2, axis=-1)
        return bool(np.max(gain) <= NOISE_GAIN)

    @cached_property
    def _basis(self) -> CubicSpline | None:
        """The spline of `_spline_weights` through the K readings' times, built once
        (None for K ≤ 3: a parabola or a line needs none)."""
        return _unit_spline(self.t) if len(self.t) > 3 and np.all(np.diff(self.t) > 0) else None

    def rate_at(self, t: ArrayLike) -> FloatArray:
        """S(t): the dark-subtracted reference rate (counts/s) at run times ``t`` (s)."""
        return np.asarray(self.weights(t) @ self.rate, dtype=np.float64)

    def dark_rounding_at(self, t: ArrayLike) -> FloatArray:
        """1σ (counts/s) of the dark rate's shared rounding error at run times ``t``."""
        if self.dark_rounding is None:
            return np.zeros(np.shape(t))
        return np.asarray(self.weights(t, spline=False) @ self.dark_rounding, dtype=np.float64)

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
        """(f, σ_f) of samples (see the module docstring); arrays (N,), pairs (N, 3).
        Computed in blocks of samples (`BLOCK_ENTRIES`): the interpolation's weights are
        a samples × calibrations matrix."""
        block = max(1, BLOCK_ENTRIES // len(self.t))
        parts = [
            self._brdf(*(a[i : i + block] for a in (counts, std, n, exposure_s, wi, wo, t)))
            for i in range(0, len(t), block)
        ]
        if not parts:
            return np.zeros(0), np.zeros(0)
        f, sigma = zip(*parts, strict=True)
        return np.concatenate(f), np.concatenate(sigma)

    def _brdf(
        self,
        counts: FloatArray,
        std: FloatArray,
        n: np.ndarray,
        exposure_s: FloatArray,
        wi: FloatArray,
        wo: FloatArray,
        t: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        w, line = self.weights(t), self.weights(t, spline=False)
        d = line @ self.dark_rate
        s = counts / exposure_s - d
        big_s = w @ self.rate
        g_ref = float(relative_geometry(self.source_kind, self.wi, self.wo))  # type: ignore[arg-type]
        g = relative_geometry(self.source_kind, wi, wo)  # type: ignore[arg-type]
        scale = self.albedo / math.pi * g_ref / np.where(g > 0, g, 1.0)
        f = scale * s / big_s
        modelled = self.noise_a + self.noise_b * np.maximum(counts - d * exposure_s, 0.0)
        own = (n >= 2) & np.isfinite(std)
        var_counts = np.where(own, std**2 / np.maximum(n, 1), modelled / np.maximum(n, 1))
        var_s = var_counts / exposure_s**2 + line**2 @ self.dark_rate_var
        var_big = w**2 @ self.rate_var
        # the dark's rounding error δ in s and S alike: ∂f/∂δ = scale·(s − S)/S²
        rounding = np.zeros_like(t) if self.dark_rounding is None else line @ self.dark_rounding
        shared = rounding * (s - big_s) / big_s**2
        sigma = scale * np.sqrt(var_s / big_s**2 + s**2 * var_big / big_s**4 + shared**2)
        return np.asarray(f, dtype=np.float64), np.asarray(sigma, dtype=np.float64)
