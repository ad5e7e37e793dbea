"""The rehearsal in numbers: the wall time per sample of `gonio acquire --rehearse`
against the bus's theoretical minimum.

The engine measures configs/plans/rehearsal.yaml (30 targets) on the arch rig wired to
hardware (configs/rigs/arch_serial.yaml): the real `DynamixelBus` on the Dynamixel
emulator, `SerialDetector` on the simulated photometer, `SerialLightSwitch` on the lamp
relay, each on its own pty, journaling durably (fsync per sample) to a run file. Time
runs 10⁶ times faster than real time, so moves, settle dwells and exposures take no
wall time: what is left is the communication and the software. Per sample, between the
first and the last (the calibrations at the start and end left out), median of the
runs: the wall time and its parts (motors: move, settle polls, read back; the
photometer's round trip; the journal's commit), the Dynamixel traffic and its wire time
(bytes × 10 / baud + the motors' 500 µs return delay per status packet), against the
theoretical minimum of one step: a SYNC_WRITE of the 4 goals, one poll that finds the
axes settled and one that reads them back (benchmarks/bus.py's hold step + poll). The
emulator times the bytes on the wire at 57 600 and 1 000 000 baud (as benchmarks/bus.py),
or answers at once ("no wire time": the software alone). Prints a markdown table.

Then the prediction against the instrument: the same plan rehearsed at real speed
(`--speedup 1`), the emulator timing every byte, at each baud rate; the run's instrument
time from the end of the first sample's reading to the end of the last's (the journal's
stamps: the calibrations left out) against the plan's predicted duration of those steps
(`gonio plan`'s: the moves at the rates the motors' profile registers hold, settle,
exposure and the bus's wire time of each step, `Rig.bus_time`). A rehearsal's clock
counts the host's own time too (instrument time = predicted + calibrations + speedup ×
host time, docs/explanations/acquisition.md), which is taken out: per sample, the wall
time above the wire time at 10⁶ × real time (as in the first table), measured just
before and just after each run at real speed (the machine's load drifts; the mean of
the two), times the steps. Medians of the runs, and the range of the differences. Also
the prediction before the bus and the rounding were counted (the rig file's rates, no
bus). Target: the prediction within 2 % of the instrument time less the host's.
Run: .venv/bin/python benchmarks/rehearsal.py [--runs N] [--real-runs N]
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from drivers.dynamixel import DEFAULT_RETURN_DELAY_S, step_seconds
from gonio.acquire import Engine, RunTime
from gonio.planner import Plan, load_plan_source, plan_bytes
from gonio.rig import TravelModel
from gonio.scene import load_scene
from gonio.store import Journal, open_run
from gonio.workflows import rehearsal_devices

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "configs" / "plans" / "rehearsal.yaml"
RIG = ROOT / "configs" / "rigs" / "arch_serial.yaml"
SCENE = load_scene(ROOT / "configs" / "scenes" / "matte.yaml")
SPEEDUP = 1e6
AXES = 4
BAUDS = (57_600, 1_000_000)


def minimum_ms(baud: int) -> float:
    """One step's theoretical minimum: a SYNC_WRITE of the goals and two polls, one that
    finds the axes settled and the read back (ms; `step_seconds` of a step that does not
    move)."""
    return float(step_seconds(AXES, baud, 0.0)) * 1e3


def plan_at(baud: int, folder: Path) -> Plan:
    """The rehearsal plan on the serial arch rig at ``baud``; health checked only at
    the start (at 10⁶ × real time its every 5 minutes would be every sample)."""
    rig = yaml.safe_load(RIG.read_text(encoding="utf-8"))
    rig["bus"]["baud"] = baud
    rig_path = folder / f"rig-{baud}.yaml"
    rig_path.write_text(yaml.safe_dump(rig, sort_keys=False), encoding="utf-8")
    plan = yaml.safe_load(PLAN.read_text(encoding="utf-8"))
    plan["rig"] = str(rig_path)
    plan["acquisition"] = {"health": {"every_minutes": None}}
    plan_path = folder / f"plan-{baud}.yaml"
    plan_path.write_text(yaml.safe_dump(plan, sort_keys=False), encoding="utf-8")
    return load_plan_source(plan_path).build()


class Timer:
    """Wall seconds spent in the wrapped calls, counted from `arm` on."""

    def __init__(self) -> None:
        self.spent = 0.0
        self.armed = False

    def wrap(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: Any, **kwargs: Any) -> Any:
            t = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                if self.armed:
                    self.spent += time.perf_counter() - t

        return timed


class Window:
    """`gonio.acquire.observer.Observer` that opens the measuring window after the first
    sample and closes it after the last: wall time, traffic and the timers inside it."""

    def __init__(self, emulator: Any, timers: list[Timer]) -> None:
        self.emulator, self.timers = emulator, timers
        self.t0 = self.t1 = 0.0
        self.samples = 0
        self.stats: Any = None

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        self.last = len(todo)

    def advance(self, done: int) -> None:
        if done == 1:
            self.emulator.reset_stats()
            for timer in self.timers:
                timer.armed = True
            self.t0 = time.perf_counter()
        elif done == self.last:
            self.t1 = time.perf_counter()
            self.stats = self.emulator.stats
            for timer in self.timers:
                timer.armed = False
            self.samples = done - 1

    def close(self) -> None:
        pass


def run_once(
    plan: Plan, folder: Path, wire_time: bool, speedup: float = SPEEDUP
) -> dict[str, float]:
    """One rehearsal of ``plan``: the figures of the window from the first sample to the
    last, per sample, and the instrument time over it (s, the journal's stamps)."""
    rig = plan.rig
    with rehearsal_devices(rig, SCENE, None, speedup, wire_time=wire_time) as (devices, clock):
        side: Any = devices.simulation
        motors, photometer, journal_timer = Timer(), Timer(), Timer()
        bus: Any = devices.bus
        for name in ("move_to", "wait_settled", "positions"):
            setattr(bus, name, motors.wrap(getattr(bus, name)))
        detector: Any = devices.detector
        detector.measure = photometer.wrap(detector.measure)
        window = Window(side.peers.emulator, [motors, photometer, journal_timer])
        meta = {"axes": list(rig.axes), "coordinate_names": list(plan.coordinate_names)}
        path = folder / "run.sqlite"
        with Journal.create(path, meta, plan_bytes(plan), durable=True, overwrite=True) as j:
            j.start_session("bench", {})
            j.sample = journal_timer.wrap(j.sample)  # type: ignore[method-assign]
            engine = Engine(plan, devices, j, side, RunTime(clock.now), progress=window)
            report = engine.run()
        if report.outcome != "completed":
            raise SystemExit(f"the rehearsal ended early: {report.message}")
    ended = np.sort(open_run(path).samples["ended_s"])
    n, stats = window.samples, window.stats
    baud = rig.spec.bus.baud
    traffic = stats.bytes_in + stats.bytes_out
    return {
        "instrument_s": float(ended[-1] - ended[0]),
        "wall_ms": (window.t1 - window.t0) / n * 1e3,
        "motors_ms": motors.spent / n * 1e3,
        "photometer_ms": photometer.spent / n * 1e3,
        "journal_ms": journal_timer.spent / n * 1e3,
        "bytes": traffic / n,
        "polls": stats.instructions["SYNC_READ"] / n,
        "writes": stats.instructions["SYNC_WRITE"] / n,
        **(
            {
                "wire_ms": (traffic * 10 / baud + stats.packets_out * DEFAULT_RETURN_DELAY_S)
                / n
                * 1e3
            }
            if wire_time
            else {}
        ),
    }


def measure(baud: int, wire_time: bool, runs: int) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        plan = plan_at(baud, folder)
        results = [run_once(plan, folder, wire_time) for _ in range(runs)]
    row = {k: statistics.median(r[k] for r in results) for k in results[0]}
    if wire_time:  # without it the emulator answers at once: no minimum to compare with
        row["minimum_ms"] = minimum_ms(baud)
        row["ratio"] = row["wall_ms"] / row["minimum_ms"]
        row["motors_ratio"] = row["motors_ms"] / row["minimum_ms"]
    return row


def predicted(plan: Plan) -> dict[str, float]:
    """The plan's predicted time (s) of the steps after its first target (those between
    the first sample and the last): moves, settle + exposure, the bus; and the moves at
    the rig file's rates, as predicted before the registers and the bus were counted."""
    rig = plan.rig
    dwell = rig.spec.settle_s + plan.exposure_s * plan.averages
    bus = rig.bus_time(plan.travel_s)
    configured = TravelModel(rig.velocity, rig.acceleration).time(plan.angles[:-1], plan.angles[1:])
    return {
        "predicted_s": float((plan.travel_s + dwell + bus)[1:].sum()),
        "bus_s": float(bus[1:].sum()),
        "before_s": float((configured + dwell[1:]).sum()),
    }


def host_ms(plan: Plan, folder: Path) -> float:
    """The host's own time a sample (ms): the wall time above the wire time of one
    rehearsal at 10⁶ × real time with wire time."""
    fast = run_once(plan, folder, True)
    return fast["wall_ms"] - fast["wire_ms"]


def at_real_speed(baud: int, runs: int) -> dict[str, float]:
    """``runs`` rehearsals at real speed with wire time, each less the host's time (the
    mean of `host_ms` just before and just after it), against the plan's prediction."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        plan = plan_at(baud, folder)
        host = [host_ms(plan, folder)]
        instrument = []
        for _ in range(runs):
            instrument.append(run_once(plan, folder, True, speedup=1.0)["instrument_s"])
            host.append(host_ms(plan, folder))
    steps = len(plan) - 1
    hosts = [0.5e-3 * (a + b) * steps for a, b in itertools.pairwise(host)]
    less = [i - h for i, h in zip(instrument, hosts, strict=True)]
    row = {"steps": steps, **predicted(plan)}
    errors = [100.0 * (row["predicted_s"] / x - 1.0) for x in less]
    row |= {
        "instrument_s": statistics.median(instrument),
        "host_s": statistics.median(hosts),
        "less_host_s": statistics.median(less),
        "error": statistics.median(errors),
        "error_low": min(errors),
        "error_high": max(errors),
        "error_raw": statistics.median(100.0 * (row["predicted_s"] / i - 1.0) for i in instrument),
        "error_before": statistics.median(100.0 * (row["before_s"] / x - 1.0) for x in less),
    }
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--real-runs", type=int, default=3, help="runs at real speed (each ~1 min)")
    args = ap.parse_args()
    columns = {
        "57 600 baud": measure(57_600, True, args.runs),
        "1 000 000 baud": measure(1_000_000, True, args.runs),
        "no wire time (57 600)": measure(57_600, False, args.runs),
    }
    print(f"machine: {describe()}")
    print(
        f"rehearsal plan (30 targets) on arch_serial, 4 axes, {SPEEDUP:.0e} × real time, "
        f"median of {args.runs} runs, per sample\n"
    )
    print("| per sample | " + " | ".join(columns) + " |")
    print("| --- |" + " ---: |" * len(columns))
    lines = [
        ("wall time, ms", "wall_ms", ".2f"),
        ("of which motors (move, settle polls, read back), ms", "motors_ms", ".2f"),
        ("of which the photometer (one MEAS round trip), ms", "photometer_ms", ".2f"),
        ("of which the journal (durable commit), ms", "journal_ms", ".2f"),
        ("Dynamixel bytes on the line", "bytes", ".0f"),
        ("SYNC_READ polls", "polls", ".2f"),
        ("SYNC_WRITEs", "writes", ".2f"),
        ("wire time of that traffic (bytes × 10 / baud + return delays), ms", "wire_ms", ".2f"),
        ("theoretical minimum (SYNC_WRITE + 2 polls), ms", "minimum_ms", ".2f"),
        ("wall / minimum", "ratio", ".2f"),
        ("motors / minimum", "motors_ratio", ".2f"),
    ]
    for label, key, fmt in lines:
        cells = [format(c[key], fmt) if key in c else "—" for c in columns.values()]
        print(f"| {label} | " + " | ".join(cells) + " |")
    real = {baud: at_real_speed(baud, args.real_runs) for baud in BAUDS}
    steps = next(iter(real.values()))["steps"]
    print(
        f"\nat real speed (--speedup 1), wire time on, median of {args.real_runs} runs: the "
        f"{steps:.0f} steps from the first sample's reading to the last's\n"
    )
    print("| at real speed | " + " | ".join(f"{b:,} baud".replace(",", " ") for b in BAUDS) + " |")
    print("| --- |" + " ---: |" * len(BAUDS))
    rows = [
        ("instrument time, s", "instrument_s", ".3f"),
        ("host time (wall − wire time a sample at 10⁶ × real time, × steps), s", "host_s", ".3f"),
        ("instrument time less host time, s", "less_host_s", ".3f"),
        ("predicted (registers' rates, settle, exposure, bus), s", "predicted_s", ".3f"),
        ("of which the bus's wire time, s", "bus_s", ".3f"),
        ("predicted / (instrument − host) − 1, %", "error", "+.2f"),
        ("predicted / instrument − 1 (host time left in), %", "error_raw", "+.2f"),
        ("predicted before (rig file's rates, no bus), s", "before_s", ".3f"),
        ("before / (instrument − host) − 1, %", "error_before", "+.2f"),
    ]
    for label, key, fmt in rows:
        print(f"| {label} | " + " | ".join(format(real[b][key], fmt) for b in BAUDS) + " |")
        if key == "error":
            cells = [f"{real[b]['error_low']:+.2f} … {real[b]['error_high']:+.2f}" for b in BAUDS]
            print("| its range over the runs, % | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The rehearsal: wall time per sample")
