"""The backends a run can drive, built from the rig file.

- ``simulated``: the rig's ``bus.kind`` is ``simulated``: virtual motors, detector and
  light on a virtual clock (`sim.virtual.devices.instrument.SimulatedInstrument`); the scene
  supplies material, noise and faults. Its journal commits without fsync and a resumed
  run restores the virtual instrument exactly where the journal left it.
- ``hardware``: ``bus.kind: dynamixel``: the real `DynamixelBus`, the rig's serial
  detector (or, with ``detector.interface: simulated``, the simulated detector reading
  the real bus's positions) and light switch, on the system clock; every sample is
  committed durably; the reference standard is put in view by the operator.
- ``rehearsal`` (``--rehearse``): the hardware path without hardware: the byte-level
  Dynamixel emulator on a pseudo-terminal in place of the motors (`sim.rehearsal`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import IO, Literal

from drivers.base import Clock, StageTarget, SystemClock
from drivers.devices import Devices
from drivers.dynamixel.bus import DynamixelBus
from gonio.acquire import RunTime, Stage, wall_offset
from gonio.errors import GonioError
from gonio.rig import Rig
from gonio.scene import Scene
from gonio.workflows.hardware import hardware_devices
from gonio.workflows.rehearsal import rehearsal_devices
from sim.rehearsal import RehearsalSide
from sim.virtual import SimDetector, SimLightSource, SimulatedInstrument, Streams

BackendKind = Literal["simulated", "hardware", "rehearsal"]


@dataclass
class Backend:
    """The devices of a run and how the engine treats them."""

    kind: BackendKind
    devices: Devices
    stage: Stage
    time: RunTime
    durable: bool  # commit every sample with fsync
    calibrate_on_resume: bool
    stack: ExitStack = field(default_factory=ExitStack)  # what must outlive the run

    def close(self) -> None:
        self.stack.close()


class OperatorStage:
    """The operator swaps the sample and the reference standard when asked (a prompt on
    the terminal); without a terminal the run cannot read its reference."""

    def __init__(self, ask: Callable[[str], str] | None = None, out: IO[str] | None = None):
        self._ask = ask
        self._out = out or sys.stderr
        self._showing: StageTarget = "sample"

    def can_ask(self) -> bool:
        return self._ask is not None or sys.stdin.isatty()

    def show(self, target: StageTarget) -> None:
        if target == self._showing:
            return
        what = "the reference standard" if target == "reference" else "the sample"
        if self._ask is None:
            if not sys.stdin.isatty():
                raise GonioError(
                    f"the run needs {what} put on the stage and no one can be asked (no "
                    "terminal): run gonio acquire from a terminal"
                )
            self._ask = input
        print(f"put {what} on the stage, then press Enter", file=self._out, flush=True)
        self._ask("")
        self._showing = target


def kind_of(rig: Rig, rehearse: bool) -> BackendKind:
    if rehearse:
        return "rehearsal"
    return "simulated" if rig.spec.bus.kind == "simulated" else "hardware"


def needs_scene(rig: Rig, kind: BackendKind) -> bool:
    """A scene is needed wherever the detector is simulated (in a rehearsal, a serial
    detector's simulated peer measures the scene too)."""
    return kind != "hardware" or rig.spec.detector.interface.kind == "simulated"


def simulated(rig: Rig, scene: Scene, seed: int | None, *, any_detector: bool = False) -> Backend:
    """``any_detector``: simulate the rig's detector whatever its interface says."""
    if rig.spec.detector.interface.kind != "simulated" and not any_detector:
        raise GonioError(
            f"{rig.source}: detector.interface: a simulated rig (bus.kind: simulated) needs "
            "a simulated detector; use --rehearse to try a serial detector without hardware"
        )
    instrument = SimulatedInstrument(scene, rig, seed=seed)
    return Backend(
        "simulated",
        instrument.devices(),
        instrument,
        RunTime(instrument.clock.now),
        durable=False,
        calibrate_on_resume=False,
    )


def hardware(
    rig: Rig,
    scene: Scene | None,
    seed: int | None,
    run_started_unix: float,
    stage: Stage | None = None,
) -> Backend:
    clock = SystemClock()
    if rig.spec.detector.interface.kind == "simulated":
        assert scene is not None  # needs_scene: the caller checked
        devices = _with_simulated_detector(rig, scene, seed, clock)
    else:
        devices = hardware_devices(rig, clock=clock)
    time = RunTime(clock.now, wall_offset(clock.now(), run_started_unix))
    # A simulated detector sees a simulated reference standard; a real one needs hands.
    stage = stage or devices.simulation or OperatorStage()
    return Backend("hardware", devices, stage, time, durable=True, calibrate_on_resume=True)


def _with_simulated_detector(rig: Rig, scene: Scene, seed: int | None, clock: Clock) -> Devices:
    bus = DynamixelBus(
        rig.spec.bus.port, rig.bus_axes(), baud=rig.spec.bus.baud, retries=rig.spec.bus.retries
    )
    light = SimLightSource()
    detector = SimDetector(
        scene,
        rig,
        bus.positions,
        clock=clock,
        streams=Streams(scene.seed if seed is None else seed),
        light=light,
    )
    return Devices(bus, detector, clock, light, RehearsalSide(detector, bus.positions))


def rehearsal(
    rig: Rig, scene: Scene, seed: int | None, run_started_unix: float, speedup: float
) -> Backend:
    stack = ExitStack()
    devices, clock = stack.enter_context(rehearsal_devices(rig, scene, seed, speedup))
    time = RunTime(clock.now, wall_offset(clock.now(), run_started_unix))
    stage = devices.simulation
    assert stage is not None
    return Backend(
        "rehearsal", devices, stage, time, durable=True, calibrate_on_resume=True, stack=stack
    )


def build(
    kind: BackendKind,
    rig: Rig,
    scene: Scene | None,
    seed: int | None,
    run_started_unix: float,
    *,
    speedup: float = 50.0,
    any_detector: bool = False,
) -> Backend:
    if kind == "simulated":
        assert scene is not None  # needs_scene: the caller checked
        return simulated(rig, scene, seed, any_detector=any_detector)
    if kind == "rehearsal":
        assert scene is not None
        return rehearsal(rig, scene, seed, run_started_unix, speedup)
    return hardware(rig, scene, seed, run_started_unix)
