"""What a run file says about its run, as figures (`figures`, the JSON of ``gonio info
--json``), the recovered BRDF's error against a truth (`error_figures`), and a simulated
run's truth (`truth_of`) at the pairs its optics saw (`measured_pairs`)."""

from __future__ import annotations

import json
from collections import Counter
from typing import Any

import numpy as np

from gonio.analysis.calibrated import calibrate, is_level
from gonio.analysis.scene import scene_alignment, scene_truth
from gonio.errors import GonioError
from gonio.store import Run
from gonio.types import FloatArray


def figures(run: Run) -> dict[str, Any]:
    """The run's figures (JSON values)."""
    plan = run.plan
    skips = run.of_kind("skip")
    faults = run.of_kind("fault")
    pauses = run.of_kind("pause")
    calibrations = run.of_kind("calibration")
    times = [e.t_s for e in run.events] + run.samples["ended_s"].tolist()
    out: dict[str, Any] = {
        "path": str(run.path),
        "plan": plan.spec.name,
        "rig": plan.rig.spec.name,
        "backend": run.meta["backend"],
        "seed": run.meta.get("seed"),
        "created_utc": run.meta["created_utc"],
        "sessions": len(run.sessions),
        "outcome": run.sessions[-1].outcome if run.sessions else None,
        "complete": run.complete,
        "targets": len(plan),
        "measured": len(run),
        "skipped": int(run.skipped.size),
        "missing": int(run.missing().size),
        "instrument_time_s": float(max(times) - min(times)) if times else 0.0,
        "predicted_s": plan.summary.total_s,
        "saturated": int(np.count_nonzero(run.samples["saturated"])),
        "remeasured": int(np.count_nonzero(run.samples["remeasured"])),
        "retries": len(run.of_kind("retry")),
        "faults": [dict(e.data, target=e.target) for e in faults],
        "skip_reasons": dict(Counter(_reason(e.data.get("reason", "")) for e in skips)),
        "pauses": [dict(e.data, t_s=e.t_s) for e in pauses],
        "calibrations": len(calibrations),
        "unit": str(calibrations[0].data.get("unit", "counts")) if calibrations else "counts",
        "phase_drifts": len(run.of_kind("phase")),
        "range_changes": len(run.of_kind("range")),
    }
    if plan.sweeps is not None:  # a fly plan's sweeps
        outcomes = Counter(s.outcome for s in run.sweeps)
        out["sweeps"] = {
            "planned": len(plan.sweeps),
            "measured": outcomes["measured"],
            "abandoned": outcomes["abandoned"],
        }
    if calibrations:
        first, last = calibrations[0].data, calibrations[-1].data
        out["reference_albedo"] = float(first["albedo"])
        out["reference_geometry_deg"] = [
            float(np.degrees(np.arccos(np.clip(first[w][2], -1.0, 1.0)))) for w in ("wi", "wo")
        ]
        out["reference_counts"] = float(first["reference"]["value"])
        out["reference_exposure_s"] = float(first["reference"]["exposure_s"])
        dark = first["dark"]
        out["dark_counts_per_s"] = (
            None
            if dark is None
            else float(dark["value"]) / (1.0 if is_level(first) else float(dark["exposure_s"]))
        )
        out["dark_reason"] = first.get("dark_reason") if dark is None else None
        out["reference_phase_deg"] = first["reference"].get("phase_deg")
        out["drift"] = _rate(last) / _rate(first) - 1.0
    return out


def _rate(data: Any) -> float:
    ref, dark = data["reference"], data["dark"]
    counts = float(ref["value"]) - (0.0 if dark is None else float(dark["value"]))
    return counts / (1.0 if is_level(data) else float(ref["exposure_s"]))


def _reason(reason: str) -> str:
    """A skip's reason without its particulars (the kind of problem)."""
    return reason.split(":", 1)[0]


def error_figures(
    run: Run, truth: FloatArray, *, recovered: FloatArray | None = None
) -> dict[str, float | int]:
    """Recovered BRDF against ``truth`` at the samples (unsaturated, truth > 0)."""
    if recovered is None:
        recovered = calibrate(run).brdf
    ok = ~run.samples["saturated"] & (truth > 0)
    error = np.abs(recovered[ok] / truth[ok] - 1.0)
    if not error.size:
        return {"n": 0}
    q50, q95 = np.percentile(error, [50, 95])
    return {
        "n": int(error.size),
        "median": float(q50),
        "p95": float(q95),
        "max": float(error.max()),
    }


def measured_pairs(run: Run) -> tuple[FloatArray, FloatArray]:
    """(ωi, ωo) the optics really saw: from the simulated backend's true joint angles
    (its journaled state) through the stored scene's ``misalignment`` when every sample
    has them, else from the read-back angles."""
    states = run.samples["sim_state"]
    if len(states) and all(s is not None for s in states):
        true = np.array([json.loads(s)["true_rad"] for s in states], dtype=np.float64)
        text = run.meta.get("scene_text")
        rig = run.plan.rig
        alignment = None if text is None else scene_alignment(str(text), rig.axes)
        return rig.forward(true, alignment)
    return run.directions()


def truth_of(run: Run, *, at_true_pairs: bool = False) -> FloatArray:
    """The simulated scene's model at the samples' read-back pairs, or at the pairs the
    optics really saw (``at_true_pairs``: they differ by the motors' position errors);
    `GonioError` unless the run stored a scene."""
    text = run.meta.get("scene_text")
    if text is None:
        raise GonioError(f"{run.path}: the run has no scene: no truth to compare with")
    scene_path = run.meta.get("scene_path")
    model = scene_truth(str(text), None if scene_path is None else str(scene_path))
    wi, wo = measured_pairs(run) if at_true_pairs else run.directions()
    return np.asarray(model(wi, wo), dtype=np.float64)
