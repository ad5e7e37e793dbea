"""The laboratory instruments driven through PyMeasure: the time per reading of each
against the instrument's own settle or integration time.

Each instrument with a preset (the SR830 lock-in amplifier, the PM100USB power meter,
the Keithley 6517B electrometer and the Keithley 2000 multimeter) is served by its
emulator on a pty and driven by its unmodified PyMeasure class over pyvisa-py, as in
`gonio acquire --rehearse`. In real time, with a 50 ms exposure: the wall time of one
reading (median of 20, after one), the time the instrument itself needs for it (the
lock-in: the exposure the driver waits, at least its 99 % settle time of 10.1 τ at
24 dB/oct, shown too; the power meter: its averaging count × 0.3 ms; the meters: their
NPLC at 50 Hz), what is left (the commands' round trips through PyMeasure, PyVISA and
the pty) and the commands per reading. Then the whole rehearsal plan
(configs/plans/rehearsal.yaml, 30 targets) with each instrument at 10⁶ × real time,
where exposures, moves and settle dwells take no wall time: the wall time per sample
and the detector's part of it (between the first and the last sample, median of 3).
Run: .venv/bin/python benchmarks/instruments.py
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe
from rehearsal import Timer, Window

from drivers.base import SystemClock
from drivers.pymeasure import SETTLE_TAU
from drivers.pymeasure.detector import PyMeasureDetector
from gonio.acquire import Engine, RunTime
from gonio.planner import load_plan_source, plan_bytes
from gonio.rig import PyMeasureInterfaceSpec
from gonio.scene import load_scene
from gonio.store import Journal
from gonio.workflows import rehearsal_devices
from sim.peers import EMULATORS, FULL_SCALE

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "configs" / "plans" / "rehearsal.yaml"
RIG = ROOT / "configs" / "rigs" / "arch_lockin.yaml"
SCENE = load_scene(ROOT / "configs" / "scenes" / "matte.yaml")
EXPOSURE_S = 0.05
READINGS = 20
INSTRUMENTS = {
    "SR830": "pymeasure.instruments.srs.SR830",
    "PM100USB": "pymeasure.instruments.thorlabs.ThorlabsPM100USB",
    "Keithley 6517B": "pymeasure.instruments.keithley.Keithley6517B",
    "Keithley 2000": "pymeasure.instruments.keithley.Keithley2000",
}


def interface(cls: str, resource: str) -> dict[str, Any]:
    return {
        "kind": "pymeasure",
        "instrument": cls,
        "resource": resource,
        "read_termination": EMULATORS[cls].terminator,
    }


def real_time(cls: str) -> dict[str, float]:
    """One instrument's readings in real time (ms)."""
    device = EMULATORS[cls](lambda t: 0.1 * FULL_SCALE[cls])
    device.start()
    try:
        spec = PyMeasureInterfaceSpec.model_validate(
            {**interface(cls, f"ASRL{device.path}::INSTR"), "visa_library": "@py"}
        )
        config = spec.config()
        with PyMeasureDetector(config, clock=SystemClock()) as det:
            det.measure(EXPOSURE_S)
            sent = len(device.commands)
            walls, realised = [], EXPOSURE_S
            for _ in range(READINGS):
                t = time.perf_counter()
                reading = det.measure(EXPOSURE_S)
                walls.append(time.perf_counter() - t)
                realised = reading.exposure_s or EXPOSURE_S
            commands = (len(device.commands) - sent) / READINGS
    finally:
        device.stop()
    wall = statistics.median(walls) * 1e3
    row = {"wall_ms": wall, "own_ms": realised * 1e3, "commands": commands}
    exposure = config.exposure
    if exposure.kind == "time_constant":
        tau = exposure.time_constant(EXPOSURE_S, det.time_constants)
        row["settle_ms"] = exposure.settle_tau * tau * 1e3
        row["tau_ms"] = tau * 1e3
    row["overhead_ms"] = wall - row["own_ms"]
    return row


def rehearsed(cls: str, folder: Path, runs: int = 3) -> dict[str, float]:
    """The rehearsal plan with this instrument at 10⁶ × real time (ms per sample)."""
    rig = yaml.safe_load(RIG.read_text(encoding="utf-8"))
    rig["detector"]["interface"] = interface(cls, "GPIB0::8::INSTR")
    rig_path = folder / "rig.yaml"
    rig_path.write_text(yaml.safe_dump(rig, sort_keys=False), encoding="utf-8")
    plan_data = yaml.safe_load(PLAN.read_text(encoding="utf-8"))
    plan_data["rig"] = str(rig_path)
    plan_data["acquisition"] = {"health": {"every_minutes": None}}
    plan_path = folder / "plan.yaml"
    plan_path.write_text(yaml.safe_dump(plan_data, sort_keys=False), encoding="utf-8")
    plan = load_plan_source(plan_path).build()
    results = []
    for _ in range(runs):
        with rehearsal_devices(plan.rig, SCENE, None, 1e6) as (devices, clock):
            side: Any = devices.simulation
            timer = Timer()
            detector: Any = devices.detector
            detector.measure = timer.wrap(detector.measure)
            window = Window(side.peers.emulator, [timer])
            meta = {"axes": list(plan.rig.axes), "coordinate_names": list(plan.coordinate_names)}
            path = folder / "run.sqlite"
            with Journal.create(path, meta, plan_bytes(plan), durable=True, overwrite=True) as j:
                j.start_session("bench", {})
                report = Engine(plan, devices, j, side, RunTime(clock.now), progress=window).run()
            if report.outcome != "completed":
                raise SystemExit(f"the rehearsal ended early: {report.message}")
        n = window.samples
        results.append(
            {"sample_ms": (window.t1 - window.t0) / n * 1e3, "detector_ms": timer.spent / n * 1e3}
        )
    return {k: statistics.median(r[k] for r in results) for k in results[0]}


def main() -> None:
    rows = {name: real_time(cls) for name, cls in INSTRUMENTS.items()}
    with tempfile.TemporaryDirectory() as tmp:
        for name, cls in INSTRUMENTS.items():
            rows[name].update(rehearsed(cls, Path(tmp)))
    print(f"machine: {describe()}")
    print(
        f"each instrument's emulator on a pty, its PyMeasure class over pyvisa-py; a "
        f"{EXPOSURE_S * 1e3:.0f} ms exposure, median of {READINGS} readings; the rehearsal "
        f"plan (30 targets) at 10⁶ × real time, median of 3 runs\n"
    )
    print("| | " + " | ".join(rows) + " |")
    print("| --- |" + " ---: |" * len(rows))
    lines = [
        ("wall time of one reading, ms", "wall_ms", ".1f"),
        ("the instrument's own time (exposure waited or integrated), ms", "own_ms", ".1f"),
        (
            f"the lock-in's time constant τ and its settle time ({SETTLE_TAU[24]} τ), ms",
            "settle_ms",
            ".1f",
        ),
        ("left for the round trips (wall − own), ms", "overhead_ms", ".1f"),
        ("commands per reading", "commands", ".0f"),
        ("rehearsal at 10⁶ × real time: wall time per sample, ms", "sample_ms", ".1f"),
        ("of which the detector, ms", "detector_ms", ".1f"),
    ]
    for label, key, fmt in lines:
        cells = []
        for row in rows.values():
            if key == "settle_ms" and key in row:
                cells.append(f"{row['tau_ms']:g} / {row[key]:.1f}")
            else:
                cells.append(format(row[key], fmt) if key in row else "—")
        print(f"| {label} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Laboratory instruments: time per reading")
