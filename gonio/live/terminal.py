"""``gonio watch``'s text: a run's figures (`gonio.live.views.overview`) as the lines a
terminal redraws in place (`screen`, with the last samples' angles and values:
`last_samples`), or as one plain line when stdout is not a terminal (`line`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from gonio.live.model import LiveRun
from gonio.live.views import values


def duration(s: float | None) -> str:
    """``1 h 02 min``, ``3 min 04 s``, ``5 s``, or ``–`` (unknown)."""
    if s is None or not math.isfinite(s):
        return "–"
    s = max(0, round(s))
    h, m, sec = s // 3600, (s % 3600) // 60, s % 60
    return f"{h} h {m:02d} min" if h else f"{m} min {sec:02d} s" if m else f"{sec} s"


def _bar(fraction: float, width: int) -> str:
    full = round(max(0.0, min(1.0, fraction)) * width)
    return "#" * full + "." * (width - full)


def line(o: Mapping[str, Any]) -> str:
    """One plain line: the state, the samples, the progress, the rate and the ETA."""
    rate = o["rate_per_s"]
    return (
        f"{o['name']}: {o['state']}, {o['measured']}/{o['targets']} samples "
        f"({100 * o['progress']:.1f} %), {o['skipped']} skipped, "
        f"{'–' if rate is None else f'{rate:.2f}'} samples/s, ETA {duration(o['eta_s'])}"
    )


def _event(e: Mapping[str, Any]) -> str:
    skip = {"id", "kind", "target", "t_s", "utc"}
    detail = ", ".join(f"{k}={v}" for k, v in e.items() if k not in skip)
    target = "" if e["target"] is None else f" target {e['target']}"
    return f"{e['utc'][11:19]} {e['kind']}{target}: {detail}"


def last_samples(live: LiveRun, count: int = 3) -> list[str]:
    """The last ``count`` samples, a line each: the target, the pair's angles (degrees)
    and the value with its 1σ (the BRDF in sr⁻¹ once the run has a calibration, else
    the reading per second; `gonio.live.views.values`)."""
    s = live.samples
    n = len(s["target"])
    if not n:
        return []
    index = np.arange(max(n - count, 0), n)
    f, sigma, unit = values(live, index)
    angles = {}
    for w in ("wi", "wo"):
        x, y, z = (s[f"{w}_{c}"][index] for c in "xyz")
        angles[w] = (
            np.degrees(np.arccos(np.clip(z, -1.0, 1.0))),
            np.degrees(np.arctan2(y, x)) % 360.0,
        )
    (ti, pi), (to, po) = angles["wi"], angles["wo"]
    out = [f"last samples (θi φi θo φo in degrees; f ± 1σ in {unit}):"]
    for k, i in enumerate(index):
        out.append(
            f"  target {int(s['target'][i])}: {ti[k]:5.1f} {pi[k]:5.1f} {to[k]:5.1f} "
            f"{po[k]:5.1f}  f {f[k]:.4g} ± {sigma[k]:.2g} (t = {float(s['ended_s'][i]):.1f} s)"
        )
    return out


def screen(live: LiveRun, o: Mapping[str, Any], *, width: int = 80, height: int = 24) -> list[str]:
    """The lines of the terminal view, at most ``height`` of at most ``width`` chars:
    the progress, the times, the last samples, the last health reading and the last
    events."""
    rate = o["rate_per_s"]
    out = [
        f"gonio watch {o['name']}   [{o['state']}]   plan {o['plan']} on {o['rig']}",
        f"[{_bar(o['progress'], max(width - 30, 10))}] {100 * o['progress']:5.1f} %",
        f"samples {o['measured']} of {o['targets']}, {o['skipped']} skipped"
        + (" (fly)" if o["fly"] else ""),
        f"instrument time {duration(o['instrument_time_s'])} "
        f"(predicted for these {duration(o['predicted_done_s'])}; "
        f"the plan {duration(o['predicted_s'])})",
        f"rate {'–' if rate is None else f'{rate:.2f} samples/s'}   ETA {duration(o['eta_s'])}",
    ]
    if o["resume"]:
        out.append(f"resume with: {o['resume']}")
    out.extend(last_samples(live))
    if o["health"]:
        h = o["health"][-1]
        temps = ", ".join(f"{a} {v:g}" for a, v in h["temperatures_c"].items())
        volts = min(h["voltages_v"].values(), default=math.nan)
        out.append(f"health: °C {temps}; supply ≥ {volts:g} V")
    if o["calibrations"]:
        drift = o["calibrations"][-1]["drift"] or 0.0
        out.append(f"calibrations {len(o['calibrations'])}, drift {100 * drift:+.3f} %")
    room = max(height - len(out) - 2, 0)
    if room and o["events"]:
        out.append("events:")
        out.extend(f"  {_event(e)}" for e in o["events"][-(room - 1 or 1) :])
    out.append("q or Ctrl-C: quit (the run goes on)")
    return [s[:width] for s in out[:height]]
