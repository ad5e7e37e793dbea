"""What each injected fault should have caused, computed from the scene's rules with
the simulator's own `sim.virtual.faults.FaultInjector`, matched with the journal's events."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from gonio.scene import MOTOR_KINDS, FaultRule
from sim.virtual.devices.detector import DETECTOR_KINDS
from sim.virtual.faults import FaultInjector
from sim.virtual.physics.streams import FAULT, Streams
from tests.soak.journal import Event, Journal
from tests.soak.loop import Soak

#: The first calibration reading's sample index (`gonio.acquire.reference`: reading
#: ``k`` of the reference uses this + 2k, its dark + 2k + 1).
CALIBRATION_INDEX = 1 << 40


@dataclass(frozen=True)
class Struck:
    """An injected fault that strikes: its rule, the sample and the attempt."""

    rule: FaultRule
    index: int
    attempt: int
    device: Literal["motor", "detector"]


def struck(
    rules: Sequence[FaultRule], seed: int, indices: np.ndarray, attempts: int
) -> list[Struck]:
    """Every (sample, attempt < ``attempts``) at which a rule strikes, by device, for
    the sample ``indices`` (as `FaultInjector.fired` decides: the first rule of a
    device's kinds that fires)."""
    streams = Streams(seed)
    injector = FaultInjector(tuple(rules), streams)
    # Vectorized first pass: which samples any rule may strike at all.
    candidates = np.zeros(len(indices), dtype=np.bool_)
    for k, r in enumerate(rules):
        if r.at is not None:
            candidates |= np.isin(indices, np.array(r.at, dtype=np.int64))
        elif r.rate:
            u = streams.uniform(indices, FAULT + k, 1)[:, 0]
            candidates |= u < r.rate
    out = []
    devices: tuple[tuple[Literal["motor", "detector"], frozenset[str]], ...] = (
        ("motor", MOTOR_KINDS),
        ("detector", DETECTOR_KINDS),
    )
    for i in indices[candidates].tolist():
        for a in range(attempts):
            for device, kinds in devices:
                rule = injector.fired(i, a, kinds)
                if rule is not None:
                    out.append(Struck(rule, int(i), a, device))
    return out


def fault_class(rule: FaultRule) -> str:
    """The name a fault is reported under."""
    if rule.kind == "comm_error":
        burst = f", bursts of {rule.burst}" if rule.burst > 1 else ""
        return f"status packet {rule.packet}{burst}"
    if rule.kind == "motor_fault":
        return f"motor {', '.join(rule.flags)}"
    if rule.kind == "detector_error":
        return "detector timeout" + (f", bursts of {rule.burst}" if rule.burst > 1 else "")
    if rule.kind == "overheat":
        return f"overheat ({rule.for_s / 3600:g} h)" if rule.for_s >= 3600 else "overheat"
    if rule.kind == "supply_sag":
        return f"supply sag ({rule.for_s / 3600:g} h)" if rule.for_s >= 3600 else "supply sag"
    return rule.kind.replace("_", " ")


# -- the story the journal tells ----------------------------------------------------------


@dataclass
class Story:
    """Each injected fault matched with its handling in the journal, and each handling
    event with a fault; ``classes``: per fault class, (struck, handled, how);
    ``problems``: what does not match."""

    classes: dict[str, tuple[int, int, str]] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    counts: Counter[str] = field(default_factory=Counter)  # events by kind
    outcomes: Counter[str] = field(default_factory=Counter)  # sessions by outcome
    instrument_s: float = 0.0  # virtual time covered
    paused_s: float = 0.0  # of it, in health pauses


def _error_of(event: Event) -> str:
    if event.kind == "skip":
        return str(event.data.get("reason", "")).split(" ", 1)[0]
    return str(event.data.get("error", ""))


_HANDLING = {
    "comm_error": "CommError",
    "detector_error": "DetectorError",
    "motor_fault": "MotorFault",
    "motion_timeout": "MotionTimeout",
}


def story(soak: Soak, journal: Journal) -> Story:
    """Match the faults the scene's rules strike with the journal's events (see
    `Story`), and the sessions with the processes the soak ran."""
    out = Story()
    rules = tuple(FaultRule.model_validate(r) for r in soak.faults)
    n = journal.targets
    calibrations = len(journal.of_kind("calibration"))
    indices = np.concatenate(
        [np.arange(n, dtype=np.int64), CALIBRATION_INDEX + np.arange(2 * calibrations + 4)]
    )
    strikes = struck(rules, soak.seed, indices, 16)
    handling = [e for e in journal.events if e.kind in ("retry", "skip", "fault")]
    by_key: dict[tuple[int, str], list[Event]] = {}
    for e in handling:
        state = e.data.get("sim_state") or {}
        by_key.setdefault((int(state.get("sample", e.target or -1)), _error_of(e)), []).append(e)
    explains = {(s.index, _HANDLING[s.rule.kind]) for s in strikes if s.rule.kind in _HANDLING}
    measured = set(journal.samples["target"].tolist())
    rows = journal.samples["target"].tolist()
    remeasured = dict(zip(rows, journal.samples["remeasured"].tolist(), strict=True))
    settled = dict(zip(rows, journal.samples["settled_s"].tolist(), strict=True))
    pauses = [e for e in journal.of_kind("pause") if e.data.get("reason") == "health"]
    tally: dict[str, list[int]] = {}
    hows: dict[str, Counter[str]] = {}
    for s in strikes:
        if s.attempt > 0:
            continue  # a burst is one fault
        name = fault_class(s.rule)
        counts = tally.setdefault(name, [0, 0])
        how = hows.setdefault(name, Counter())
        calibration = s.index >= CALIBRATION_INDEX
        if s.rule.kind in _HANDLING:
            events = by_key.get((s.index, _HANDLING[s.rule.kind]), [])
            if not events:
                if calibration or s.index not in measured:
                    continue  # not reached: a calibration not taken, a sample skipped before
                out.problems.append(f"{name} at sample {s.index}: no handling event")
                counts[0] += 1
                continue
            counts[0] += 1
            counts[1] += 1
            kinds = {e.kind for e in events}
            where = " in a calibration" if calibration else ""
            if "skip" in kinds:
                how[f"skipped by policy after {len(events) - 1} retries"] += 1
            elif "fault" in kinds:
                how[f"stopped resumable{where}, resumed"] += 1
            else:
                how[f"retried ×{len(events)}{where}"] += 1
        elif s.rule.kind == "saturated":
            if calibration or s.index not in measured:
                continue
            counts[0] += 1
            if remeasured.get(s.index, 0) > 0:
                counts[1] += 1
                how["measured again at a shorter exposure"] += 1
            else:
                out.problems.append(f"{name} at sample {s.index}: not measured again")
        elif s.rule.kind in ("overheat", "supply_sag") and not calibration:
            counts[0] += 1
            t0 = settled.get(s.index)
            if t0 is None:
                out.problems.append(f"{name} at sample {s.index}: the sample is missing")
                continue
            word = "°C" if s.rule.kind == "overheat" else "supply"
            seen = [
                p for p in pauses
                if t0 - 600 <= p.t_s <= t0 + s.rule.for_s
                and any(word in q for q in p.data["problems"])
            ]  # fmt: skip
            if seen:
                counts[1] += 1
                how["paused (health), went on when it cleared"] += 1
            else:
                how["not seen by a health check"] += 1
    for name, (a, b) in tally.items():
        out.classes[name] = (a, b, "; ".join(f"{k}: {v}" for k, v in sorted(hows[name].items())))
    for e in journal.events:
        out.counts[e.kind] += 1
    for key, events in by_key.items():
        if key not in explains:
            out.problems.append(f"{len(events)} {events[0].kind} events at sample {key[0]} "
                                f"({key[1]}): no injected fault")  # fmt: skip
    # Sessions: each ends as its process did; each after the first starts with a resume.
    first_event: dict[int, Event] = {}
    for e in journal.events:
        first_event.setdefault(e.session, e)
    processes = {s.pid: s for s in soak.sessions}
    finished_before = 0
    done_by_session: Counter[int] = Counter(journal.samples["session"].tolist())
    for e in journal.of_kind("skip"):
        done_by_session[e.session] += 1
    for k, (sid, outcome, pid) in enumerate(journal.sessions):
        out.outcomes[outcome or "none (killed or disk full)"] += 1
        proc = processes.get(pid)
        head = first_event.get(sid)
        if head is not None:
            want = "start" if k == 0 else "resume"
            if head.kind != want:
                out.problems.append(f"session {sid} begins with {head.kind}, not {want}")
            elif k and head.data.get("targets_left") != n - finished_before:
                out.problems.append(
                    f"session {sid}: resume says {head.data.get('targets_left')} targets left, "
                    f"the journal {n - finished_before}"
                )
        finished_before += done_by_session[sid]
        if proc is None:
            out.problems.append(f"session {sid}: no process of the soak had pid {pid}")
            continue
        if proc.killed and outcome is not None:
            pass  # killed while closing, after the session's end was written
        elif proc.returncode == 0 and outcome != "completed":
            out.problems.append(f"session {sid}: exit 0 but outcome {outcome}")
        elif proc.returncode == 3 and outcome not in ("fault", "paused", "journal", None):
            out.problems.append(f"session {sid}: exit 3 but outcome {outcome}")
        elif proc.returncode == 3 and outcome is None and not proc.disk_full:
            out.problems.append(f"session {sid}: exit 3 and no outcome, the disk was not full")
    for p in pauses:
        if not any("°C" in q or "supply" in q for q in p.data["problems"]):
            out.problems.append(f"pause event {p.id}: no injected overheat or sag explains it")
    ends = journal.samples["ended_s"].astype(np.float64)
    times = [e.t_s for e in journal.events]
    out.instrument_s = float(max(ends.max(initial=0.0), max(times, default=0.0)))
    out.paused_s = float(sum(e.data.get("paused_s", 0.0) for e in journal.of_kind("resume")))
    return out
