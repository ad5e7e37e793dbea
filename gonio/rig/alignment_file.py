"""The alignment file: a rig's measured misalignment (`AlignmentSpec`: degrees,
millimetres, axes by name) with how it was measured — every fitted parameter with its
standard error, what the scan could not determine and what would, the residuals, the
date, the scan's run and the rig file it was fitted for (`AlignmentFile`).

`from_fit` makes one from `gonio.rig.alignment_fit.fit`; `text` writes it as YAML
(``# gonio alignment v1``), `load_alignment` reads it back with the configuration
loader's one-line errors.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import numpy as np
import yaml
from pydantic import Field, model_validator

from gonio.config import MAX_INTEGER, Strict, load
from gonio.errors import GonioError
from gonio.rig.alignment_spec import MAX_ERROR_DEG, MAX_HEIGHT_MM, AlignmentSpec
from gonio.types import FloatArray

if TYPE_CHECKING:  # annotations only: the rig model reads alignment files (`load_alignment`)
    from gonio.rig.alignment_fit import AlignmentFit
    from gonio.rig.model import Rig

#: The first line of an alignment file.
HEADER = "# gonio alignment v1"
#: The largest standard error or residual an alignment file may state (° or mm): a
#: parameter known no better than this is not determined.
MAX_STATED = 90.0

Stated = Annotated[float, Field(ge=0, le=MAX_STATED)]
Correlation = Annotated[float, Field(ge=-1, le=1)]
#: How far a stated correlation matrix may be from symmetric, unit-diagonal and positive
#: semi-definite (the rounding of its written decimals).
CORRELATION_TOLERANCE = 1e-6


class FittedParameter(Strict):
    """One fitted parameter: its value and standard error (° for angles, mm for the
    height)."""

    value: float = Field(ge=-MAX_STATED, le=MAX_STATED, description="The fitted value (°, mm).")
    error: Stated = Field(description="Its standard error (°, mm).")


class FitRecord(Strict):
    """How an alignment was measured."""

    date_utc: str = Field(description="When it was fitted (ISO 8601, UTC).")
    run: str = Field(description="The scan's run file, as given to gonio align.")
    run_sha256: str = Field(description="The sha256 of the scan's run file when fitted.")
    rig: str = Field(description="The rig's name.")
    rig_sha256: str = Field(description="The sha256 of the rig file's text it was fitted for.")
    peaks: int = Field(ge=1, le=MAX_INTEGER, description="The specular peaks fitted.")
    chi2: float = Field(ge=0, le=1e300, description="χ² of the peaks' misses at the fit.")
    dof: int = Field(ge=0, le=MAX_INTEGER, description="Its degrees of freedom.")
    residual_rms_deg: Stated = Field(description="The peaks' rms miss at the fit (°).")
    residual_max_deg: Stated = Field(description="The peaks' largest miss at the fit (°).")
    parameters: dict[str, FittedParameter] = Field(
        description="Each determined parameter (names of gonio.rig.alignment_fit)."
    )
    correlation: list[list[Correlation]] | None = Field(
        None,
        description="The fitted parameters' correlation matrix, rows and columns in the "
        "order of parameters (none: taken as independent).",
    )
    undetermined: dict[str, str] = Field(
        default_factory=dict,
        description="Each parameter the scan could not determine, with why and what would.",
    )

    @model_validator(mode="after")
    def _square(self) -> FitRecord:
        rows = self.correlation
        if rows is None:
            return self
        n = len(self.parameters)
        if len(rows) != n or any(len(r) != n for r in rows):
            raise ValueError(f"correlation: expected {n} rows of {n}, one per parameter")
        matrix = np.array(rows)
        if not np.allclose(np.diag(matrix), 1.0, atol=CORRELATION_TOLERANCE):
            raise ValueError("correlation: expected 1 on the diagonal")
        if not np.allclose(matrix, matrix.T, atol=CORRELATION_TOLERANCE):
            raise ValueError("correlation: expected a symmetric matrix")
        if np.linalg.eigvalsh(0.5 * (matrix + matrix.T)).min() < -CORRELATION_TOLERANCE:
            raise ValueError("correlation: expected a positive semi-definite matrix")
        return self

    def covariance(self) -> FloatArray:
        """The stated covariance (P, P) of `parameters` in their order (°², mm², °·mm):
        standard errors and correlations (independent where the file gives none)."""
        errors = np.array([p.error for p in self.parameters.values()], dtype=np.float64)
        n = len(errors)
        rho = np.eye(n) if self.correlation is None else np.array(self.correlation)
        return np.asarray(errors[:, None] * rho * errors[None, :], dtype=np.float64)


class AlignmentFile(Strict):
    """A rig's measured misalignment and how it was measured."""

    alignment: AlignmentSpec = Field(description="The misalignment the rig model applies.")
    fit: FitRecord | None = Field(None, description="How it was measured (none: set by hand).")


def _degrees(name: str, value: float) -> float:
    return value if name == "height_mm" else math.degrees(value)


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def from_fit(
    result: AlignmentFit, rig: Rig, rig_text: bytes, run: Path, run_bytes: bytes, date_utc: str
) -> AlignmentFile:
    """The alignment file of a fit of the scan in ``run`` for ``rig`` (its file's text)."""
    values = dict(zip(result.names, result.values, strict=True))
    a = result.alignment
    angles = {name: math.degrees(v) for name, v in values.items() if name != "height_mm"}
    worst = max(angles, key=lambda name: abs(angles[name]))
    if abs(angles[worst]) > MAX_ERROR_DEG or abs(values["height_mm"]) > MAX_HEIGHT_MM:
        raise GonioError(
            f"alignment fit: {worst} = {angles[worst]:.3g}° (or the height "
            f"{values['height_mm']:.3g} mm) is beyond what an alignment corrects "
            f"({MAX_ERROR_DEG:g}°, {MAX_HEIGHT_MM:g} mm): check the rig's assembly and its file"
        )
    spec = AlignmentSpec(
        zero_offset_deg={name: angles[f"zero_offset.{name}"] for name in rig.axes},
        tilt_deg=math.degrees(float(a.tilt)),
        tilt_azimuth_deg=math.degrees(float(a.tilt_azimuth)),
        height_mm=float(values["height_mm"]),
        light_pointing_deg=(angles["light_pointing_x"], angles["light_pointing_y"]),
        detector_pointing_deg=(angles["detector_pointing_x"], angles["detector_pointing_y"]),
    )
    misses = np.degrees(np.hypot(*result.residuals_rad.T))
    kept = np.flatnonzero(result.determined)
    block = result.covariance[np.ix_(kept, kept)]
    scale = np.sqrt(np.diag(block))
    correlation = np.clip(block / np.outer(scale, scale), -1.0, 1.0)
    np.fill_diagonal(correlation, 1.0)
    record = FitRecord(
        date_utc=date_utc,
        run=str(run),
        run_sha256=sha256(run_bytes),
        rig=rig.spec.name,
        rig_sha256=sha256(rig_text),
        peaks=len(result.residuals_rad),
        chi2=result.chi2,
        dof=result.dof,
        residual_rms_deg=float(np.sqrt(np.mean(misses**2))),
        residual_max_deg=float(misses.max()),
        parameters={
            name: FittedParameter(value=_degrees(name, v), error=_degrees(name, e))
            for name, v, e, ok in zip(
                result.names, result.values, result.errors, result.determined, strict=True
            )
            if ok
        },
        correlation=correlation.tolist(),
        undetermined=dict(result.hints),
    )
    return AlignmentFile(alignment=spec, fit=record)


def text(file: AlignmentFile) -> str:
    """The YAML of an alignment file, its header first."""
    body = yaml.safe_dump(file.model_dump(mode="json"), sort_keys=False, allow_unicode=True)
    return f"{HEADER}\n{body}"


def load_alignment(path: str | Path, raw: bytes | None = None) -> AlignmentFile:
    """An alignment file (`ConfigError`, one line naming the file and the field, on any
    mistake)."""
    return load(path, AlignmentFile, raw=raw)


__all__ = [
    "HEADER",
    "AlignmentFile",
    "FitRecord",
    "FittedParameter",
    "from_fit",
    "load_alignment",
    "sha256",
    "text",
]
