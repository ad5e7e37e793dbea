"""A run's samples as named columns with units: what the csv, hdf5 and bluesky exports
write, one entry per measured target in target order (docs/reference/formats.md#columns).

A column's ``key`` carries its unit as a suffix (``_rad``, ``_s``, ``_per_sr``; the
detector's readings are ``counts`` and ``counts_std``; none for a unitless value or an
index), so a reader needs no other file; ``unit`` spells it for attributes (``rad``,
``s``, ``sr^-1``, ``counts``, ``""``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio import params
from gonio.analysis import calibrate
from gonio.store import Run, schema


@dataclass(frozen=True)
class Column:
    """One per-sample quantity: ``key`` (with its unit suffix), ``unit``, what it is,
    and its values (N,) as float64, int64, bool or str."""

    key: str
    unit: str
    description: str
    values: np.ndarray


_SUFFIX = {"rad": "_rad", "s": "_s", "sr^-1": "_per_sr", "counts": "", "": ""}


def _column(name: str, unit: str, description: str, values: np.ndarray) -> Column:
    return Column(name + _SUFFIX[unit], unit, description, values)


def coordinate_unit(name: str) -> str:
    """A plan coordinate's unit: angles (θ…, φ…) in rad, norms (‖h̄‖, ‖k‖…) unitless."""
    return "rad" if name.startswith(("theta", "phi")) else ""


def sample_columns(run: Run) -> list[Column]:
    """Every exported column of ``run`` (`GonioError` for a run without a calibration:
    its BRDF values cannot be computed)."""
    s = run.samples
    wi, wo = run.directions()
    calibrated = calibrate(run)
    angles = params.get("spherical").forward(wi, wo) if len(run) else np.empty((0, 4))
    cols = [
        _column("target", "", "index of the target in the stored plan", s["target"]),
        _column("session", "", "the session (process) that measured it", s["session"]),
        _column("attempts", "", "tries it took (1 = first)", s["attempts"]),
        _column("utc", "", "wall time when it was journaled (ISO 8601 UTC)", s["utc"].astype(str)),
    ]
    for name, (vectors, what) in {
        "wi": (wi, "toward the light"),
        "wo": (wo, "toward the detector"),
    }.items():
        for j, axis in enumerate("xyz"):
            cols.append(
                _column(
                    f"{name}_{axis}",
                    "",
                    f"{axis} of the unit direction {what} (sample frame, z = normal; "
                    "from the read-back angles)",
                    vectors[:, j],
                )
            )
    for j, (name, what) in enumerate(
        (
            ("theta_i", "polar angle of wi"),
            ("phi_i", "azimuth of wi, [0, 2π)"),
            ("theta_o", "polar angle of wo"),
            ("phi_o", "azimuth of wo, [0, 2π)"),
        )
    ):
        cols.append(_column(name, "rad", what, angles[:, j]))
    for name in run.meta["coordinate_names"]:
        cols.append(
            _column(
                f"coord_{name}",
                coordinate_unit(name),
                f"the plan's coordinate {name} ({run.plan.spec.parametrization})",
                s[schema.coordinate(name)],
            )
        )
    for axis in run.axes:
        for which, stored in (("commanded", schema.commanded), ("read_back", schema.read_back)):
            cols.append(
                _column(
                    f"{axis}_{which}",
                    "rad",
                    f"axis {axis}: the pose {which.replace('_', ' ')}",
                    s[stored(axis)],
                )
            )
    cols += [
        _column("exposure", "s", "exposure the detector integrated", s["exposure_s"]),
        _column("averages", "", "exposures asked", s["averages"]),
        _column("n", "", "exposures averaged", s["n"]),
        _column("counts", "counts", "mean reading of the n exposures", s["counts"]),
        _column(
            "counts_std",
            "counts",
            "their standard deviation (0 for n = 1; empty/NaN when the device gave none)",
            s["counts_std"],
        ),
        _column("saturated", "", "the kept reading hit full scale", s["saturated"]),
        _column("remeasured", "", "times measured again at half the exposure", s["remeasured"]),
        _column("settled", "s", "run time when the motors settled", s["settled_s"]),
        _column("started", "s", "run time when the first exposure began", s["started_s"]),
        _column("ended", "s", "run time when the last exposure ended", s["ended_s"]),
        _column(
            "brdf",
            "sr^-1",
            "calibrated BRDF value (cosine factor excluded)",
            calibrated.brdf,
        ),
        _column("sigma", "sr^-1", "its 1σ uncertainty", calibrated.sigma),
    ]
    return cols
