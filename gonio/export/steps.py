"""The long steps of an export, each shown while it runs (`gonio.progress`: on a terminal,
unless quiet): reading and calibrating the run, reconstructing it, evaluating the
reconstruction at many pairs (`BLOCK` pairs at a time, the bar advancing with each
block), factorizing, building documents, writing.
"""

from __future__ import annotations

from contextlib import AbstractContextManager

import numpy as np

from gonio import progress
from gonio.analysis import Measured
from gonio.errors import GonioError
from gonio.export import MIN_SUPPORTED
from gonio.reconstruct import reconstruction, values_and_support
from gonio.store import Run
from gonio.types import BoolArray, Evaluable, FloatArray, Surface

#: Pairs evaluated at once by `evaluated`: each block advances its bar.
BLOCK = 1 << 16


def sparse_note(supported: int, total: int, what: str, *, allow: bool) -> str:
    """`GonioError` (one line) when the run's samples support less than
    `MIN_SUPPORTED` of the ``total`` ``what`` of a grid, unless ``allow``: then the
    warning line to print (``"warning: …"``); "" when enough is supported."""
    share = supported / total if total else 0.0
    if share >= MIN_SUPPORTED:
        return ""
    said = (
        f"the run's samples support {share:.1%} of the {what} ({supported:,} of {total:,}); "
        f"the rest would be the reconstruction's extrapolation"
    )
    if not allow:
        raise GonioError(
            f"{said}: expected at least {MIN_SUPPORTED:.0%} (measure more targets, or give "
            "--allow-sparse to export anyway)"
        )
    return f"warning: {said} (below {MIN_SUPPORTED:.0%}; written as asked by --allow-sparse)"


def step(description: str) -> AbstractContextManager[progress.Progress]:
    """An export step that cannot count (one call into compiled code), named while it runs."""
    return progress.step(description, work="export")


def reconstructed(
    run: Run,
    method: str,
    parametrization: str | None = None,
    *,
    extrapolate: str | None = None,
    allow_sparse: bool = False,
) -> tuple[Measured, Surface]:
    """The run's calibrated samples and their reconstruction by ``method``
    (`gonio.reconstruct.methods.reconstruction`), each step shown; `GonioError` (one
    line) for a run of fewer samples than one simplex of its coordinates holds (d + 1:
    every value of a grid would be copied from a sample), unless ``allow_sparse``."""
    with step("reading and calibrating the run"):
        measured = Measured.from_run(run)
    simplex = (3 if measured.isotropic else 4) + 1
    if len(measured) < simplex and not allow_sparse:
        raise GonioError(
            f"the run has {len(measured)} calibrated sample{'s' * (len(measured) != 1)}: "
            f"expected at least {simplex}, one simplex of its {simplex - 1} coordinates, "
            "before a grid is filled from them (measure more targets, or give --allow-sparse "
            "to export anyway)"
        )
    with step(f"reconstructing ({method}) from {len(measured):,} samples"):
        surface = reconstruction(measured, method, parametrization, extrapolate=extrapolate)
    return measured, surface


def evaluated(
    surface: Evaluable, wi: FloatArray, wo: FloatArray, description: str
) -> tuple[FloatArray, BoolArray | None]:
    """`gonio.reconstruct.result.values_and_support` of ``surface`` at the pairs (..., 3)
    (broadcast against each other), `BLOCK` pairs at a time, shown as ``description``
    with a bar of pairs: values (...) plus a trailing 3 for RGB, and where the surface
    has data (None when it does not say). Each pair's value is the one an evaluation
    of all of them at once gives."""
    a, b = np.broadcast_arrays(np.asarray(wi, dtype=np.float64), np.asarray(wo, dtype=np.float64))
    lead = a.shape[:-1]
    a, b = a.reshape(-1, 3), b.reshape(-1, 3)
    values: list[FloatArray] = []
    support: list[BoolArray | None] = []
    with progress.stage(description, len(a), unit="pair", work="export") as shown:
        for start in range(0, max(len(a), 1), BLOCK):
            f, ok = values_and_support(surface, a[start : start + BLOCK], b[start : start + BLOCK])
            values.append(np.asarray(f, dtype=np.float64))
            support.append(ok)
            shown.advance(len(values[-1]))
    f = np.concatenate(values).reshape(*lead, *values[0].shape[1:])
    if any(ok is None for ok in support):
        return f, None
    return f, np.concatenate([ok for ok in support if ok is not None]).reshape(lead)
