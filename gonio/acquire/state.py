"""What the engine carries from target to target and from one session of a run to the
next (`RunState`), and how a resumed session rebuilds it from the run's journal
(`initial_state`, `latest_snapshot`), so it goes on where the journal ends."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from gonio.acquire.schedule import Calibrations, Every
from gonio.planner import AcquisitionSpec
from gonio.store import Run, dumps


@dataclass
class RunState:
    """The run's state across targets and sessions: ``count`` targets measured (all
    sessions), the `Calibrations`, when a health check is due (``health_due``), the
    temperatures the last health check read (JSON text, journaled with the next sample,
    then None) and whether the last health check found a problem (``unhealthy``, as the
    journal left it)."""

    calibrations: Calibrations
    health_due: Every
    count: int = 0
    temperatures: str | None = None
    unhealthy: bool = False


def initial_state(spec: AcquisitionSpec, history: Run | None) -> RunState:
    """The state a session starts from: a new run's (``history`` None), or where the
    run's journal ``history`` ends (its last calibration and health check)."""
    cal, health = spec.calibration, spec.health
    state = RunState(
        Calibrations(Every(cal.every_samples, cal.every_minutes)),
        Every(health.every_samples, health.every_minutes),
    )
    if history is None:
        return state
    state.count = len(history)
    calibrations = history.of_kind("calibration")
    if calibrations:
        last = calibrations[-1]
        exposure_s = float(last.data["reference"]["exposure_s"])
        state.calibrations.done(int(last.data["count"]), last.t_s, exposure_s)
    state.calibrations.k = len(calibrations)
    checks = history.of_kind("health")
    if checks:
        last_check = checks[-1].data
        state.health_due.done(int(last_check["count"]), checks[-1].t_s)
        state.unhealthy = bool(last_check["problems"] or last_check["flags"])
        if int(last_check["count"]) == state.count:  # the next sample's temperatures
            state.temperatures = dumps(dict(last_check["temperatures_c"]))
    return state


def latest_snapshot(history: Run) -> Any:
    """The simulated backend's state when the journal's last entry was written (None if
    the journal holds none)."""
    best: tuple[float, int, Any] | None = None
    states = history.samples["sim_state"]
    if len(states) and states[-1] is not None:
        k = int(np.argmax(history.samples["ended_s"]))
        best = (float(history.samples["ended_s"][k]), 0, json.loads(states[k]))  # stored as text
    for e in history.events:
        if "sim_state" in e.data and (best is None or (e.t_s, 1) >= best[:2]):
            best = (e.t_s, 1, e.data["sim_state"])
    return None if best is None else best[2]
