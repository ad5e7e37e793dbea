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
Run: .venv/bin/python benchmarks/rehearsal.py [--runs N]
"""

from __future__ import annotations

import argparse
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

from gonio.acquire.engine import Engine
from gonio.acquire.runtime import RunTime
from gonio.planner.files import load_plan_source, plan_bytes
from gonio.planner.model import Plan
from gonio.store.journal import Journal
from gonio.workflows.rehearsal import rehearsal_devices
from sim.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "configs" / "plans" / "rehearsal.yaml"
RIG = ROOT / "configs" / "rigs" / "arch_serial.yaml"
SCENE = load_scene(ROOT / "configs" / "scenes" / "matte.yaml")
SPEEDUP = 1e6
RETURN_DELAY_S = 250 * 2e-6  # the motors' default Return Delay Time
AXES = 4
#: Bytes on the line of one SYNC_WRITE of 4 goals (header 4, ID, LEN 2, INST, address 2,
#: length 2, 4 × (ID + 4 bytes), CRC 2) and of one poll (benchmarks/bus.py: 18 + 4 × 25).
SYNC_WRITE_BYTES = 4 + 1 + 2 + 1 + 2 + 2 + AXES * 5 + 2
POLL_BYTES = 118


def minimum_ms(baud: int) -> float:
    """One step's theoretical minimum: a SYNC_WRITE and two polls (ms)."""
    wire = (SYNC_WRITE_BYTES + 2 * POLL_BYTES) * 10 / baud
    return (wire + 2 * AXES * RETURN_DELAY_S) * 1e3


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
    """`gonio.acquire.progress.Observer` that opens the measuring window after the first
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


def run_once(plan: Plan, folder: Path, wire_time: bool) -> dict[str, float]:
    rig = plan.rig
    with rehearsal_devices(rig, SCENE, None, SPEEDUP, wire_time=wire_time) as (devices, clock):
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
    n, stats = window.samples, window.stats
    baud = rig.spec.bus.baud
    traffic = stats.bytes_in + stats.bytes_out
    return {
        "wall_ms": (window.t1 - window.t0) / n * 1e3,
        "motors_ms": motors.spent / n * 1e3,
        "photometer_ms": photometer.spent / n * 1e3,
        "journal_ms": journal_timer.spent / n * 1e3,
        "bytes": traffic / n,
        "polls": stats.instructions["SYNC_READ"] / n,
        "writes": stats.instructions["SYNC_WRITE"] / n,
        **(
            {"wire_ms": (traffic * 10 / baud + stats.packets_out * RETURN_DELAY_S) / n * 1e3}
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
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


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The rehearsal: wall time per sample")
