"""The simulated instrument: virtual motors and a virtual detector sharing one virtual
clock and one run seed, and a rehearsal mode that drives the real `DynamixelBus`
against the byte-level emulator with the simulated detector.

`SimulatedInstrument.run(plan)` measures a plan target by target through the
`drivers.base` protocols (`move_to`, `wait_settled`, `positions`, `measure`), as the
acquisition engine does; `sim.simulate.simulate` computes the same run vectorized.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from drivers.base import Reading, Resource
from drivers.dynamixel.bus import DynamixelBus
from gonio.planner.plan import Plan
from gonio.rig.model import Rig
from gonio.types import FloatArray
from sim.clock import ManualClock, ScaledClock
from sim.devices.detector import CALIBRATION_INDEX, SimDetector, SimLightSource
from sim.devices.motors import MotorState, SimMotorBus
from sim.dynamixel.emulator import DxlEmulator
from sim.physics.streams import Streams
from sim.record import SimRun
from sim.scene import Scene
from sim.simulate import planned_poses

#: How long a simulated move may take before `wait_settled` gives up (s).
MOVE_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class InstrumentState:
    """Where a simulated run stands between targets: virtual time and the motors."""

    time_s: float
    motors: MotorState


class SimulatedInstrument(Resource):
    """`SimMotorBus` + `SimDetector` + `SimLightSource` on one `ManualClock`."""

    def __init__(
        self, scene: Scene, rig: Rig, *, seed: int | None = None, clock: ManualClock | None = None
    ) -> None:
        self.scene = scene
        self.rig = rig
        self.seed = scene.seed if seed is None else int(seed)
        self.clock = clock or ManualClock()
        self.streams = Streams(self.seed)
        self.bus = SimMotorBus(
            rig, self.clock, position_error=scene.effects.position_error, streams=self.streams
        )
        self.light = SimLightSource()
        self.detector = SimDetector(
            scene,
            rig,
            self.bus.true_positions,
            now=self.clock,
            wait=self.clock.advance,
            streams=self.streams,
            light=self.light,
        )

    def open(self) -> None:
        self.bus.open()

    def close(self) -> None:
        self.bus.close()

    def state(self) -> InstrumentState:
        """The state to `restore` a resumed run from (between targets)."""
        return InstrumentState(self.clock.now, self.bus.snapshot())

    def restore(self, state: InstrumentState) -> None:
        """Continue from ``state``: the clock (which must not be past it) and the motors."""
        if self.clock.now > state.time_s:
            raise ValueError(f"the clock is already past {state.time_s} s")
        self.clock.advance(state.time_s - self.clock.now)
        self.bus.restore(state.motors)

    def measure_target(
        self, index: int, angles: Sequence[float], exposure_s: float, averages: int
    ) -> tuple[FloatArray, Reading, float]:
        """Move to ``angles`` (rig.axes order), settle, measure with sample ``index``'s
        stream: (read-back angles, reading, virtual time when the motors settled)."""
        self.bus.sample_index = index
        self.detector.sample_index = index
        self.bus.move_to(dict(zip(self.rig.axes, angles, strict=True)))
        self.bus.wait_settled(MOVE_TIMEOUT_S)
        settled = self.clock.now
        read_back = np.array(list(self.bus.positions().values()))
        return read_back, self.detector.measure(exposure_s, averages), settled

    def measure_reference(self, k: int, angles: Sequence[float], exposure_s: float) -> Reading:
        """Measure the reference standard at ``angles`` (calibration reading k)."""
        self.detector.target = "reference"
        try:
            return self.measure_target(CALIBRATION_INDEX + k, angles, exposure_s, 1)[1]
        finally:
            self.detector.target = "sample"

    def run(
        self, plan: Plan, *, start: int = 0, stop: int | None = None, prepare: bool = True
    ) -> SimRun:
        """Measure targets ``start``…``stop`` of ``plan`` one by one (stream index =
        target index, so a run resumed at ``start`` equals the tail of a full run once
        the motors are where the full run had them). With ``prepare`` the detector first
        computes the optics at the poses the plan will reach, vectorized
        (`SimDetector.prepare`); the readings are the same either way."""
        stop = len(plan) if stop is None else stop
        rows = range(start, stop)
        if prepare:
            _, expected, _ = planned_poses(plan, self.scene, self.streams)
            self.detector.prepare(expected[start:stop])
        read_back, true, readings, settled, ends = [], [], [], [], []
        for i in rows:
            rb, reading, t = self.measure_target(
                i, plan.angles[i].tolist(), float(plan.exposure_s[i]), int(plan.averages[i])
            )
            read_back.append(rb)
            true.append(list(self.bus.true_positions().values()))
            readings.append(reading)
            settled.append(t)
            ends.append(self.clock.now)
        true_a = np.array(true, dtype=np.float64).reshape(-1, len(self.rig.axes))
        wi, wo = self.rig.forward(true_a)
        return SimRun(
            index=np.arange(start, stop, dtype=np.int64),
            commanded=plan.angles[start:stop],
            read_back=np.array(read_back, dtype=np.float64).reshape(-1, len(self.rig.axes)),
            true=true_a,
            wi=wi,
            wo=wo,
            exposure_s=plan.exposure_s[start:stop],
            averages=plan.averages[start:stop],
            settled_s=np.array(settled, dtype=np.float64),
            end_s=np.array(ends, dtype=np.float64),
            value=np.array([r.value for r in readings], dtype=np.float64),
            std=np.array([r.std for r in readings], dtype=np.float64),
            saturated=np.array([r.saturated for r in readings], dtype=np.bool_),
        )


@dataclass
class Rehearsal:
    """The real driver path without hardware: `DynamixelBus` on the emulator's pty, the
    simulated detector reading the bus's read-back positions."""

    emulator: DxlEmulator
    bus: DynamixelBus
    detector: SimDetector
    light: SimLightSource
    clock: ScaledClock


@contextmanager
def rehearsal(
    scene: Scene, rig: Rig, *, speedup: float = 50.0, seed: int | None = None
) -> Iterator[Rehearsal]:
    """An emulated bus of the rig's motors (at home), the real `DynamixelBus` on it,
    and a `SimDetector` on a clock running ``speedup`` times faster than real time."""
    clock = ScaledClock(speedup)
    axes = rig.bus_axes()
    emulator = DxlEmulator(
        ids=[a.motor_id for a in axes],
        baud=rig.spec.bus.baud,
        clock=clock,
        wire_time=False,
        return_delay=False,
    )
    for axis, home in zip(axes, rig.home, strict=True):
        motor = emulator.motors[axis.motor_id]
        motor.set("operating_mode", axis.operating_mode)
        motor.set("present_position", axis.to_ticks(float(home)))
    light = SimLightSource()
    with emulator:
        bus = DynamixelBus(emulator.path, axes, baud=rig.spec.bus.baud)
        with bus:
            detector = SimDetector(
                scene,
                rig,
                bus.positions,
                now=clock,
                wait=lambda s: time.sleep(s / speedup),
                streams=Streams(scene.seed if seed is None else seed),
                light=light,
            )
            yield Rehearsal(emulator, bus, detector, light, clock)
