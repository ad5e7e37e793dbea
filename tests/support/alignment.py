"""An alignment file's fit record as a test writes one: the given parameters as
(value, standard error) in ° (mm for the height), their correlations, the rest a
plausible scan's."""

from __future__ import annotations

from gonio.rig.alignment_file import FitRecord, FittedParameter


def fit_record(
    parameters: dict[str, tuple[float, float]], correlation: list[list[float]] | None = None
) -> FitRecord:
    return FitRecord(
        date_utc="2026-01-01T00:00:00Z",
        run="scan.sqlite",
        run_sha256="0" * 64,
        rig="arch",
        rig_sha256="0" * 64,
        peaks=20,
        chi2=1.0,
        dof=10,
        residual_rms_deg=0.01,
        residual_max_deg=0.02,
        parameters={n: FittedParameter(value=v, error=e) for n, (v, e) in parameters.items()},
        correlation=correlation,
    )
