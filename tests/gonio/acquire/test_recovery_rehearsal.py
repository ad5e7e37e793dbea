"""``acquisition.on_fault.motor: recover`` on the real driver path: the engine drives
`DynamixelBus` over the emulator's pty (the arch rig, a simulated detector, time 1000×
faster), and the emulated motors fault as real ones do — an overload latched until
REBOOT (mid-move), a supply error found at rest by a health check, a motor hot above
its Temperature Limit that cools on the run's clock. The run completes with every
target measured once and each recovery journaled; a multi-turn motor that comes back
from its reboot a turn away stops the run resumable."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio.acquire.ending import Report
from gonio.acquire.engine import Engine
from gonio.acquire.runtime import RunTime
from gonio.planner.files import load_plan_source
from gonio.planner.model import Plan
from gonio.planner.stored import plan_bytes
from gonio.scene import load_scene
from gonio.store.journal import Journal
from gonio.store.read import Run, read_run
from gonio.workflows.rehearsal import rehearsal_devices
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from sim.rehearsal import RehearsalSide
from tests.conftest import CONFIGS
from tests.support.acquire import ARCH, plan_yaml

pytestmark = pytest.mark.pty

SCENE = CONFIGS / "scenes" / "matte.yaml"
ACQUISITION = {
    "on_fault": {"motor": {"action": "recover", "max_recoveries": 2}},
    # Health checked by count only: time runs with the wall clock here.
    "health": {"poll_s": 10, "every_samples": 5, "every_minutes": None},
}


class Injecting:
    """Progress that calls ``inject(emulator, done)`` after each target measured."""

    def __init__(self, inject: Callable[[DxlEmulator, int], None]) -> None:
        self.inject = inject
        self.emulator: DxlEmulator | None = None

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        pass

    def advance(self, done: int) -> None:
        assert self.emulator is not None
        self.inject(self.emulator, done)

    def close(self) -> None:
        pass


def rehearse(
    tmp_path: Path, targets: int, inject: Callable[[DxlEmulator, int], None]
) -> tuple[Report, Run]:
    path = tmp_path / "plan.yaml"
    path.write_text(plan_yaml(targets, rig=ARCH, acquisition=ACQUISITION))
    source = load_plan_source(path)
    plan = source.build()
    progress = Injecting(inject)
    with rehearsal_devices(source.rig, load_scene(SCENE), None, 1000.0) as (devices, clock):
        side = devices.simulation
        assert isinstance(side, RehearsalSide) and side.peers is not None
        progress.emulator = side.peers.emulator
        meta = {"axes": list(source.rig.axes), "coordinate_names": list(plan.coordinate_names)}
        out = tmp_path / "run.sqlite"
        with Journal.create(out, meta, plan_bytes(plan), durable=False) as journal:
            journal.start_session("now", {})
            engine = Engine(plan, devices, journal, side, RunTime(clock.now), progress=progress)
            report = engine.run()
            run = read_run(journal.conn, out)
        assert side.peers.emulator.error is None
    return report, run


def test_an_overload_a_supply_error_and_an_overheated_motor_recover_and_the_run_completes(
    tmp_path: Path,
) -> None:
    def inject(emu: DxlEmulator, done: int) -> None:
        if done == 3:
            emu.inject(Fault.OVERLOAD, motor_id=3)  # detector_elevation
        if done == 5:  # at rest: the health check due now finds it
            emu.inject(Fault.INPUT_VOLTAGE, motor_id=4)  # sample_rotation
        if done == 6:
            emu.motors[1].heat(120.0, 600.0)  # light_elevation, above its 80 °C limit

    report, run = rehearse(tmp_path, 10, inject)
    assert report.outcome == "completed", report
    assert run.complete and sorted(run.target.tolist()) == list(range(10))
    steps = [(e.target, e.data["axis"], e.data["step"]) for e in run.of_kind("recovery")]
    assert steps == [
        (3, "detector_elevation", "diagnosed"),
        (3, "detector_elevation", "rebooted"),
        (3, "detector_elevation", "recovered"),
        *[(None, "sample_rotation", s) for s in ("diagnosed", "rebooted", "recovered")],
        *[
            (6, "light_elevation", s)
            for s in ("diagnosed", "cooling", "cooled", "rebooted", "recovered")
        ],
    ]
    diagnosed = [e.data for e in run.of_kind("recovery") if e.data["step"] == "diagnosed"]
    assert diagnosed[0]["flags"] == ["overload"] and diagnosed[0]["load_pct"] == 0.0
    assert diagnosed[1]["flags"] == ["input_voltage"]
    assert diagnosed[2]["flags"] == ["overheating"] and diagnosed[2]["temperature_c"] > 65
    cooling, cooled = (e.data for e in run.of_kind("recovery") if e.data["step"].startswith("cool"))
    # 30 + 90·exp(−t/600 s) < 65 °C 567 s after the heat, on the run's clock (which runs
    # with the wall clock here: how much of it passed before the fault was seen varies).
    assert cooling["temperature_c"] >= 65 > cooled["temperature_c"]
    assert 0 < cooled["waited_s"] <= 567 + 100
    rebooted = [e.data for e in run.of_kind("recovery") if e.data["step"] == "rebooted"]
    assert all(r["deviation_deg"] == 0.0 for r in rebooted)
    # Read back within a tick of the commanded angles, the re-measured targets too.
    tick = np.array([a.resolution_rad for a in run.plan.rig.bus_axes()])
    assert np.all(np.abs(run.angles("read_back") - run.angles("commanded")) <= tick)


def test_a_multi_turn_motor_back_a_turn_away_stops_the_run(tmp_path: Path) -> None:
    """detector_azimuth is multi-turn (extended position, 2:1): at a negative angle its
    motor's ticks are negative, and a reboot brings them back within one turn."""
    injected: list[int] = []

    def inject(emu: DxlEmulator, done: int) -> None:
        if not injected and emu.motors[2].get("present_position") < -200:
            emu.inject(Fault.OVERLOAD, motor_id=2)
            injected.append(done)

    report, run = rehearse(tmp_path, 10, inject)
    assert injected, "no target left the azimuth motor at negative ticks"
    assert report.outcome == "fault" and len(run) == injected[0]
    *_, rebooted, failed = run.of_kind("recovery")
    assert rebooted.data["deviation_deg"] > 10 and failed.data["step"] == "failed"
    assert "re-home it" in failed.data["reason"]
    (fault,) = run.of_kind("fault")
    assert fault.data["axis"] == "detector_azimuth" and "not recovered" in fault.data["message"]
