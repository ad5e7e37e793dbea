"""What a run file says about its run, as figures (`figures`, the JSON of ``gonio info
--json``) and as the table `gonio acquire`, `gonio simulate` and `gonio info` print."""

from __future__ import annotations

import json
from collections import Counter
from typing import Any

import numpy as np

from gonio.acquire.calibrated import calibrate
from gonio.errors import GonioError
from gonio.planner.plan import hms
from gonio.store.read import Run
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
            None if dark is None else float(dark["value"]) / float(dark["exposure_s"])
        )
        out["drift"] = _rate(last) / _rate(first) - 1.0
    return out


def _rate(data: Any) -> float:
    ref, dark = data["reference"], data["dark"]
    counts = float(ref["value"]) - (0.0 if dark is None else float(dark["value"]))
    return counts / float(ref["exposure_s"])


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


def render(run: Run, errors: dict[str, float | int] | None = None, *, title: bool = True) -> str:
    """The table (``title``: with a first line naming the run file, plan and rig)."""
    f = figures(run)
    lines = [
        f"run {str(run.path)!r}: plan {f['plan']!r} on rig {f['rig']!r}, "
        f"{f['backend']} backend, seed {f['seed']}",
        f"  {'outcome':<24}{f['outcome'] or 'not ended':>10}   ({f['sessions']} session"
        f"{'s' if f['sessions'] != 1 else ''})",
        f"  {'targets measured':<24}{f['measured']:>10}   of {f['targets']} "
        f"({f['skipped']} skipped, {f['missing']} missing)",
        f"  {'instrument time':<24}{hms(f['instrument_time_s']):>10}   "
        f"(the plan predicted {hms(f['predicted_s'])} without calibrations)",
        f"  {'saturated readings':<24}{f['saturated']:>10}   "
        f"({f['remeasured']} measured again at a shorter exposure)",
        f"  {'faults':<24}{len(f['faults']):>10}   ({f['retries']} retries)",
    ]
    for fault in f["faults"][-3:]:
        lines.append(f"    target {fault.get('target')}: {fault['message']}")
    for reason, count in f["skip_reasons"].items():
        lines.append(f"    skipped {count}: {reason}")
    if f["pauses"]:
        reasons = Counter(str(p.get("reason")) for p in f["pauses"])
        lines.append(
            f"  {'pauses':<24}{len(f['pauses']):>10}   "
            f"({', '.join(f'{k} {v}' for k, v in reasons.items())})"
        )
    if f["calibrations"]:
        dark = f["dark_counts_per_s"]
        ti, to = f["reference_geometry_deg"]
        lines.append(
            f"  {'calibrations':<24}{f['calibrations']:>10}   reference standard (albedo "
            f"{f['reference_albedo']:g}, {ti:.0f}°/{to:.0f}°) {f['reference_counts']:.1f} "
            f"counts at {f['reference_exposure_s']:g} s; "
            f"dark {'not read' if dark is None else f'{dark:.1f} counts/s'}; "
            f"drift {100 * f['drift']:+.3f} % by the last, divided out"
        )
    if not title:
        lines.pop(0)
    if errors is not None and errors.get("n"):
        lines.append(
            f"  {'recovered BRDF error':<24}{100 * errors['median']:>9.3f}%   median; "
            f"95th percentile {100 * errors['p95']:.3f} %, max {100 * errors['max']:.3f} % "
            f"(vs the scene's model, {errors['n']} unsaturated targets)"
        )
    return "\n".join(lines)


def measured_pairs(run: Run) -> tuple[FloatArray, FloatArray]:
    """(ωi, ωo) the optics really saw: from the simulated backend's true joint angles
    (its journaled state) when every sample has them, else from the read-back angles."""
    states = run.samples["sim_state"]
    if len(states) and all(s is not None for s in states):
        true = np.array([json.loads(s)["true_rad"] for s in states], dtype=np.float64)
        return run.plan.rig.forward(true)
    return run.directions()


def truth_of(run: Run, *, at_true_pairs: bool = False) -> FloatArray:
    """The simulated scene's model at the samples' read-back pairs, or at the pairs the
    optics really saw (``at_true_pairs``: they differ by the motors' position errors);
    `GonioError` unless the run stored a scene."""
    text = run.meta.get("scene_text")
    if text is None:
        raise GonioError(f"{run.path}: the run has no scene: no truth to compare with")
    from pathlib import Path

    from sim.physics.optics import SceneOptics
    from sim.scene import load_scene

    scene = load_scene(Path(f"{run.path}#scene_text"), run.plan.rig, raw=str(text).encode())
    wi, wo = measured_pairs(run) if at_true_pairs else run.directions()
    return np.asarray(SceneOptics(scene, run.plan.rig).models["sample"](wi, wo), dtype=np.float64)


def render_details(run: Run) -> str:
    """What `gonio info` adds to the table: the sessions, the BRDF the counts give
    through the calibration, the file."""
    lines = ["  sessions"]
    for session in run.sessions:
        info = session.info
        lines.append(
            f"    {session.id}: {session.started_utc} → {session.outcome or 'did not end (killed)'}"
            f" ({info.get('backend', '?')}, pid {info.get('pid', '?')})"
        )
    if len(run) and run.of_kind("calibration"):
        cal = calibrate(run)
        ok = np.isfinite(cal.brdf) & (cal.brdf > 0)
        rel = cal.sigma[ok] / cal.brdf[ok]
        lines.append(
            f"  {'derived BRDF':<24}{int(ok.sum()):>10}   values, {cal.brdf[ok].min():.4g} to "
            f"{cal.brdf[ok].max():.4g} sr⁻¹, median uncertainty {100 * np.median(rel):.3f} % (1σ)"
        )
    if run.path.is_file():
        size = run.path.stat().st_size
        lines.append(
            f"  {'run file':<24}{size / 1024:>9.0f}K   schema v{run.meta['schema_version']}, "
            f"{len(run.events)} events"
        )
    return "\n".join(lines)
