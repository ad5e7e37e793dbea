"""The run table `gonio acquire`, `gonio simulate` and `gonio info` print, from the
run's figures (`gonio.analysis.summary`)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

from gonio.acquire import recovery
from gonio.analysis import calibrate, figures
from gonio.progress import hms
from gonio.store import Run


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
    if run.plan.summary.second_pass is not None:  # an adaptive plan's: how and why
        lines.append(f"  {'second pass':<24}{'':>10}   {run.plan.summary.second_pass}")
    for fault in f["faults"][-3:]:
        lines.append(f"    target {fault.get('target')}: {fault['message']}")
    lines.extend(recovery.describe(run))
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
        unit = f["unit"]
        value = f["reference_counts"]
        shown = f"{value:.1f} counts" if unit == "counts" else f"{value:.4g} {unit}"
        if dark is not None:
            level = f"{dark:.1f} counts/s" if unit == "counts" else f"{dark:.4g} {unit}"
            dark_text = f"dark {level}"
        elif f["dark_reason"] == "detector":
            dark_text = "no dark reading: the detector subtracts it (lock-in)"
        else:
            dark_text = "dark not read"
        lines.append(
            f"  {'calibrations':<24}{f['calibrations']:>10}   reference standard (albedo "
            f"{f['reference_albedo']:g}, {ti:.0f}°/{to:.0f}°) {shown} "
            f"at {f['reference_exposure_s']:g} s; "
            f"{dark_text}; "
            f"drift {100 * f['drift']:+.3f} % by the last, divided out"
        )
    if f["phase_drifts"]:
        lines.append(
            f"  {'phase drifts':<24}{f['phase_drifts']:>10}   samples whose lock-in phase "
            "drifted from the reference reading's beyond the tolerance (phase events)"
        )
    if f["range_changes"]:
        lines.append(
            f"  {'range changes':<24}{f['range_changes']:>10}   the instrument auto-ranged "
            "(range events)"
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


def render_details(run: Run) -> str:
    """What `gonio info` adds to the table: the sessions, the BRDF the counts give
    through the calibration, the file."""
    lines = ["  sessions"]
    for session in run.sessions:
        info = session.info
        # A session that did not record its end: killed, crashed, or its disk full.
        ended = session.outcome or "did not end (killed, or its disk full)"
        lines.append(
            f"    {session.id}: {session.started_utc} → {ended}"
            f" ({info.get('backend', '?')}, pid {info.get('pid', '?')})"
        )
    sweeps = figures(run).get("sweeps")
    if sweeps is not None:  # a fly run
        lines.append(
            f"  {'fly':<24}sweeps measured: {sweeps['measured']} of {sweeps['planned']}, "
            f"readings: {len(run)}, abandoned: {sweeps['abandoned']}"
        )
    if len(run) and run.of_kind("calibration"):
        cal = calibrate(run)
        ok = np.isfinite(cal.brdf) & (cal.brdf > 0)
        if ok.any():
            rel = cal.sigma[ok] / cal.brdf[ok]
            lines.append(
                f"  {'derived BRDF':<24}{int(ok.sum()):>10}   values, {cal.brdf[ok].min():.4g} "
                f"to {cal.brdf[ok].max():.4g} sr⁻¹, median uncertainty "
                f"{100 * np.median(rel):.3f} % (1σ)"
            )
        else:  # every reading at or below the dark: no positive value to show
            lines.append(f"  {'derived BRDF':<24}{0:>10}   positive values (every reading ≤ dark)")
    if run.path.is_file():
        size = run.path.stat().st_size
        lines.append(
            f"  {'run file':<24}{size / 1024:>9.0f}K   schema v{run.meta['schema_version']}, "
            f"{len(run.events)} events"
        )
    return "\n".join(lines)


def alignment_line(run: Run) -> str:
    """One line: the alignment the run's rig file named (its file's name, date and
    largest determined parameter), or none."""
    rig = run.plan.rig
    file = rig.alignment_file
    if file is None:
        return f"  {'alignment':<24}{'none':>10}   (the rig file's geometry)"
    name = Path(str(run.meta.get("alignment_path") or rig.alignment_path)).name
    if file.fit is None:
        return f"  {'alignment':<24}{name:>10}   (set by hand, no fit record)"
    angles = {k: p.value for k, p in file.fit.parameters.items() if k != "height_mm"}
    if not angles:
        return f"  {'alignment':<24}{name:>10}   (fitted {file.fit.date_utc}; none determined)"
    worst = max(angles, key=lambda k: abs(angles[k]))
    return (
        f"  {'alignment':<24}{name:>10}   (fitted {file.fit.date_utc}; largest determined "
        f"parameter {worst} {angles[worst]:+.4f}°)"
    )
