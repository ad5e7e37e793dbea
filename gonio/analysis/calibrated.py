"""BRDF values and their uncertainty from a journaled run's raw counts, through its
calibration events (docs/explanations/acquisition.md#calibration): each
holds a reading of the reference
standard and a dark reading; `calibration_series` gathers them and
`gonio.radiometry.series.CalibrationSeries` inverts the samples (the formula and the
noise model are there)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError
from gonio.radiometry.series import CalibrationSeries
from gonio.store.read import Event, Run
from gonio.types import FloatArray


@dataclass(frozen=True)
class Calibrated:
    """Per sample (in the run's sample order): f (sr⁻¹) and its 1σ uncertainty."""

    brdf: FloatArray
    sigma: FloatArray
    series: CalibrationSeries


def calibration_series(events: tuple[Event, ...]) -> CalibrationSeries:
    """The series of a run's calibration events (`GonioError` without one)."""
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
    return CalibrationSeries(
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


def _std(reading: dict[str, object]) -> float:
    """A journaled reading's spread (counts); 0 where the device gave none."""
    std = reading.get("std")
    return 0.0 if std is None else float(std)  # type: ignore[arg-type]


def calibrate(run: Run) -> Calibrated:
    """The run's BRDF values and uncertainties (`GonioError` without a calibration)."""
    series = calibration_series(run.of_kind("calibration"))
    s = run.samples
    wi, wo = run.directions()
    t = 0.5 * (s["started_s"] + s["ended_s"])
    f, sigma = series.brdf(s["counts"], s["counts_std"], s["n"], s["exposure_s"], wi, wo, t)
    return Calibrated(f, sigma, series)
