"""BRDF values and their uncertainty from a journaled run's raw counts, through its
calibration events (docs/explanations/acquisition.md#calibration): each
holds a reading of the reference
standard and a dark reading; `calibration_series` gathers them and
`gonio.radiometry.series.CalibrationSeries` inverts the samples (the formula and the
noise model are there); a point source's spot fall-off is divided out where the
instrument has it (`gonio.analysis.falloff`), and a point source's distance as the
sample's measured height changes it (`gonio.analysis.lamp_distance`); the uncertainty
of the rig's measured alignment is added to σ (`gonio.analysis.alignment_error`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio.analysis.alignment_error import with_alignment_error
from gonio.analysis.falloff import spot_corrected
from gonio.analysis.lamp_distance import distance_corrected
from gonio.errors import GonioError
from gonio.radiometry import CalibrationSeries, rounding_var, student_variance
from gonio.store import Event, Run
from gonio.types import FloatArray


@dataclass(frozen=True)
class Calibrated:
    """Per sample (in the run's sample order): f (sr⁻¹) and its 1σ uncertainty."""

    brdf: FloatArray
    sigma: FloatArray
    series: CalibrationSeries


def calibration_series(events: tuple[Event, ...]) -> CalibrationSeries:
    """The series of a run's calibration events (`GonioError` without one): the noise
    model a (the dark readings' variance per exposure) and b (the reference's excess
    variance per count) pooled over them and expanded for the degrees of freedom it is
    estimated from (`noise_model`), each reading's variance from it, and the error the
    darks' rounding leaves (`gonio.radiometry.series`)."""
    if not events:
        raise GonioError("the run has no calibration reading: no BRDF can be derived")
    t, dark, ref, a_s, b_s = [], [], [], [], []
    codes, dark_counts_, dark_spread, exposures, ns, dns = [], [], [], [], [], []
    ref_dof, dark_dof = [], []
    for e in events:
        r, d = e.data["reference"], e.data["dark"]
        exposure = float(r["exposure_s"])
        if is_level(e.data):  # as integrals over the exposure (`is_level`)
            r, d = _integral(r, exposure), None if d is None else _integral(d, exposure)
        n = max(int(r["n"]), 1)
        t.append(0.5 * (float(r["started_s"]) + float(r["ended_s"])))
        if d is None:
            dark_counts, dark_std, dn = 0.0, 0.0, 1
        else:
            dark_counts, dark_std, dn = float(d["value"]), _std(d), max(int(d["n"]), 1)
        dark.append(dark_counts / exposure)
        signal = float(r["value"]) - dark_counts
        ref.append(signal / exposure)
        a_s.append(dark_std**2)
        b_s.append(max(_std(r) ** 2 - dark_std**2, 0.0) / max(signal, 1e-300))
        ref_dof.append(_dof(r, n))
        dark_dof.append(0 if d is None else _dof(d, dn))
        codes.append(d is not None and not is_level(e.data) and _whole_codes(r) and _whole_codes(d))
        dark_counts_.append(dark_counts)
        dark_spread.append(dark_std)
        exposures.append(exposure)
        ns.append(n)
        dns.append(dn if d is not None else math.inf)
    first = events[0].data
    rate = np.array(ref)
    if np.any(rate <= 0):
        raise GonioError("a reference reading is not above its dark reading: no calibration")
    exposure_s = np.array(exposures)
    model = noise_model(
        np.array(a_s), np.array(b_s), np.array(ref_dof), np.array(dark_dof), rate * exposure_s
    )
    dark_var = model.a / np.array(dns) / exposure_s**2
    ref_var = (model.a + model.b * rate * exposure_s) / np.array(ns) / exposure_s**2 + dark_var
    rounding = _dark_rounding(
        np.array(codes),
        np.array(dark_counts_),
        np.array(dark_spread),
        model.b_estimate,
        exposure_s,
    )
    return CalibrationSeries(
        albedo=float(first["albedo"]),
        source_kind=str(first["source_kind"]),
        wi=np.array(first["wi"], dtype=np.float64),
        wo=np.array(first["wo"], dtype=np.float64),
        t=np.array(t),
        dark_rate=np.array(dark),
        dark_rate_var=dark_var,
        rate=rate,
        rate_var=ref_var,
        noise_a=model.a,
        noise_b=model.b,
        dark_rounding=rounding,
        noise_dof=model.dof,
    )


@dataclass(frozen=True)
class NoiseModel:
    """The calibration's noise model var(C) = a + b·C per exposure (counts², C the
    signal in counts), expanded for its degrees of freedom (`noise_model`): ``a``, ``b``
    as the σ of every value uses them, ``b_estimate`` as pooled (the best estimate of
    the noise itself), ``dof`` the references' ν (∞: no spread to estimate from)."""

    a: float
    b: float
    b_estimate: float
    dof: float


def noise_model(
    a: FloatArray, b: FloatArray, ref_dof: np.ndarray, dark_dof: np.ndarray, signal: FloatArray
) -> NoiseModel:
    """The noise model pooled over K calibrations: ``a`` (K,) each dark reading's
    variance per exposure (counts²), ``b`` (K,) each reference's excess variance per
    count of ``signal`` (K,, counts per exposure), ``ref_dof``/``dark_dof`` (K,) the
    degrees of freedom of their spreads (n − 1; 0 where none was given).

    Each estimate is the mean of the readings' variances weighted by their degrees of
    freedom (a pooled variance, JCGM 100:2008 4.2.4 and H.3.6), so it rests on
    ν = Σ (n_k − 1) of them: ν_d for a, ν_r for the references' variance a + b·S̄ at
    their mean signal S̄. An error divided by a σ so estimated follows Student's t with
    ν degrees of freedom, whose variance is ν/(ν − 2); each of the model's two points,
    a and a + b·S̄, is multiplied by that factor of its own ν (`student_variance`), so
    the z-scores have unit variance whatever the number of exposures, and b joins them.
    The alternative, predicting the noise from the signal through a detector model,
    needs the detector's gain and read noise, which the rig file does not declare.
    `GonioError` where a variance rests on ν ≤ 2 (no finite variance: no σ)."""
    a_pooled, b_pooled = _pooled(a, dark_dof), _pooled(b, ref_dof)
    level = _pooled(signal, ref_dof) if ref_dof.sum() > 0 else float(np.mean(signal))
    nu_d, nu_r = float(dark_dof.sum()), float(ref_dof.sum())
    f_d = student_variance(nu_d) if a_pooled > 0 else 1.0
    f_r = student_variance(nu_r) if a_pooled + b_pooled * level > 0 else 1.0
    if math.isinf(f_d) or math.isinf(f_r):
        nu, what = (nu_d, "dark") if math.isinf(f_d) else (nu_r, "reference")
        raise GonioError(
            f"the calibration's {len(signal)} {what} readings estimate their noise from "
            f"{nu:g} degrees of freedom (n − 1 each, n their exposures): too few for a σ "
            "(Student's t with ν ≤ 2 has no finite variance); take at least 4 exposures a "
            "reading (acquisition.calibration.averages)"
        )
    expanded_b = max(f_r * b_pooled + (f_r - f_d) * a_pooled / level, 0.0)
    return NoiseModel(f_d * a_pooled, expanded_b, b_pooled, nu_r if nu_r > 0 else math.inf)


def _pooled(values: FloatArray, dof: np.ndarray) -> float:
    """The mean of ``values`` weighted by their degrees of freedom (0 without any)."""
    total = float(np.sum(dof))
    return float(np.dot(dof, values) / total) if total > 0 else 0.0


def _dof(reading: Mapping[str, Any], n: int) -> int:
    """The degrees of freedom of a journaled reading's spread: n − 1, 0 without one."""
    return n - 1 if reading.get("std") is not None else 0


def is_level(calibration: Mapping[str, Any]) -> bool:
    """Whether a calibration event's readings are levels (a lock-in's V, a power meter's
    W, an electrometer's A: any unit but counts), not integrals over the exposure. A
    level times its exposure is taken as the integral (V·s, …) a count would be: the
    BRDF's ratios are those of the levels whatever the exposures (a lock-in read at half
    the exposure after an overload reads the same volts, not half), and a lock-in's
    noise, its filter's bandwidth ∝ 1/exposure, then grows with the exposure as
    counting statistics do."""
    return bool(calibration.get("unit", "counts") != "counts")


def readings(run: Run) -> tuple[FloatArray, FloatArray]:
    """The samples' readings and spreads as integrals over their exposures (counts,
    or a level × its exposure: `is_level`), (N,) each."""
    calibrations = run.of_kind("calibration")
    s = run.samples
    counts, std = np.asarray(s["counts"], np.float64), np.asarray(s["counts_std"], np.float64)
    if calibrations and is_level(calibrations[0].data):
        return counts * s["exposure_s"], std * s["exposure_s"]
    return counts, std


def _integral(reading: Mapping[str, Any], exposure_s: float) -> dict[str, Any]:
    """A journaled level reading as its integral over ``exposure_s`` (`is_level`)."""
    std = reading.get("std")
    return {
        **reading,
        "value": float(reading["value"]) * exposure_s,
        "std": None if std is None else float(std) * exposure_s,
    }


def _whole_codes(reading: dict[str, object]) -> bool:
    """Whether a journaled reading is the mean of whole ADC codes (n × mean whole)."""
    total = float(reading["value"]) * max(int(reading["n"]), 1)  # type: ignore[arg-type,call-overload]
    return bool(abs(total - round(total)) <= 1e-6 * max(1.0, abs(total)))


def _dark_rounding(
    codes: np.ndarray, dark: FloatArray, spread: FloatArray, noise_b: float, exposure: FloatArray
) -> FloatArray:
    """1σ (counts/s) of the error rounding to ADC codes leaves in each dark rate
    (`gonio.radiometry.series.rounding_var`; 0 where the readings are not whole codes).

    What dithers the rounding is the dark reading's noise per exposure (codes): at
    least the shot noise of its own counts D, b·D (b the reference's variance per count
    of signal: the same counting statistics). Its spread s tells more only where it is
    at least half a code: a steady level between two codes spreads up to ½ by rounding
    alone, so a smaller spread says nothing of the noise; from ½ on, σ² = s² − 1/12
    (and the rounding error is negligible). Reading after reading of the same dark level
    rounds the same way: the error is shared by every calibration."""
    noise2 = np.where(
        spread >= 0.5, np.maximum(noise_b * dark, spread**2 - 1.0 / 12.0), noise_b * dark
    )
    noise = np.sqrt(np.maximum(noise2, 0.0))
    if not np.any(codes):
        return np.zeros(len(codes))
    return np.asarray(np.where(codes, np.sqrt(rounding_var(noise)) / exposure, 0.0), np.float64)


def _std(reading: dict[str, object]) -> float:
    """A journaled reading's spread (counts); 0 where the device gave none."""
    std = reading.get("std")
    return 0.0 if std is None else float(std)  # type: ignore[arg-type]


def calibrate(run: Run, *, falloff: bool = True) -> Calibrated:
    """The run's BRDF values and uncertainties (`GonioError` without a calibration);
    ``falloff``: divide a point source's spot fall-off out where the instrument has it."""
    series = calibration_series(run.of_kind("calibration"))
    s = run.samples
    wi, wo = run.directions()
    t = 0.5 * (s["started_s"] + s["ended_s"])
    counts, std = readings(run)
    f, sigma = series.brdf(counts, std, s["n"], s["exposure_s"], wi, wo, t)
    if falloff:
        f, sigma = spot_corrected(run, series, f, sigma)
    f, sigma = distance_corrected(run, f, sigma)
    return Calibrated(f, with_alignment_error(run, f, sigma), series)
