"""The simulated instrument: virtual motors, detector and light sharing one virtual
clock, one run seed and the scene's injected faults; and the byte-level emulator of a
rig's motors (`emulated_bus`), which the rehearsal backend (`sim.rehearsal`) drives
with the real `DynamixelBus`.

`SimulatedInstrument` is the simulated backend as the engine sees it: `devices()` gives
the `gonio.acquire.Devices` (the `drivers.base` contract), and the instrument itself is
their `drivers.base.Simulated` side (which sample comes next, sample or reference on the
stage, the true joint angles, snapshots for resume). `run(plan)` measures a plan target
by target through `gonio.acquire.measure`, the same step the engine takes;
`sim.simulate.simulate` computes the same run vectorized.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drivers.base import Resource, StageTarget
from gonio.acquire.devices import Devices
from gonio.acquire.measure import measure_target
from gonio.planner.plan import Plan
from gonio.rig.model import Rig
from sim.clock import ManualClock, TimeSource
from sim.devices.detector import SimDetector, SimLightSource
from sim.devices.motors import MotorState, SimMotorBus
from sim.dynamixel.emulator import DxlEmulator
from sim.faults import FaultInjector
from sim.physics.streams import Streams
from sim.record import SimRun
from sim.scene import Scene
from sim.simulate import planned_poses


class SimulatedInstrument(Resource):
    """`SimMotorBus` + `SimDetector` + `SimLightSource` on one `ManualClock`; the
    scene's ``faults`` are injected (``faults=False`` ignores them)."""

    def __init__(
        self,
        scene: Scene,
        rig: Rig,
        *,
        seed: int | None = None,
        clock: ManualClock | None = None,
        faults: bool = True,
    ) -> None:
        self.scene = scene
        self.rig = rig
        self.seed = scene.seed if seed is None else int(seed)
        self.clock = clock or ManualClock()
        self.streams = Streams(self.seed)
        injector = FaultInjector(scene.faults if faults else (), self.streams)
        self.bus = SimMotorBus(
            rig,
            self.clock,
            position_error=scene.effects.position_error,
            streams=self.streams,
            faults=injector,
        )
        self.light = SimLightSource()
        self.detector = SimDetector(
            scene,
            rig,
            self.bus.true_positions,
            clock=self.clock,
            streams=self.streams,
            light=self.light,
            faults=injector,
        )
        self._devices = Devices(self.bus, self.detector, self.clock, self.light, self)

    def devices(self) -> Devices:
        """The backend as the engine drives it (open it with ``with``)."""
        return self._devices

    def open(self) -> None:
        self._devices.__enter__()

    def close(self) -> None:
        self._devices.__exit__(None, None, None)

    # -- drivers.base.Simulated ------------------------------------------------------
    def begin_sample(self, index: int) -> None:
        self.bus.begin_sample(index)
        self.detector.begin_sample(index)

    def show(self, target: StageTarget) -> None:
        self.detector.show(target)

    def true_positions(self) -> dict[str, float]:
        return self.bus.true_positions()

    def expect(self, goals: np.ndarray, index: np.ndarray) -> None:
        """Compute the optics, vectorized, at the poses the motors will really reach
        moving from home to ``goals`` (N, A) in order as samples ``index``
        (`SimDetector.prepare`: a cache; readings are the same without it)."""
        _, expected, _ = planned_poses(self.rig, goals, self.scene, self.streams, index)
        self.detector.prepare(expected)

    def snapshot(self) -> dict[str, Any]:
        """The state a resumed run restores (between targets, at rest), as JSON values:
        the virtual time, the motors (`MotorState`), how many moves and readings the
        present sample has used (so a retried or resumed sample continues its streams
        and its injected faults do not fire twice) and an injected overheat in force."""
        motors = self.bus.snapshot()
        true = self.bus.true_positions()
        sample = self.bus.present_sample
        return {
            "time_s": self.clock.now(),
            "encoder": list(motors.encoder),
            "direction": list(motors.direction),
            "repeatability": list(motors.repeatability),
            "true_rad": [true[a] for a in self.rig.axes],  # what the optics saw
            "sample": sample,
            "moves": self.bus.moves_of(sample),
            "draws": self.detector.draws_of(sample),
            "overheat": self.bus.overheat,
        }

    def restore(self, state: Any) -> None:
        """Continue from a `snapshot`: the clock (which must not be past it), the
        motors, the present sample's counters and an overheat in force."""
        try:
            time_s = float(state["time_s"])
            motors = MotorState(
                tuple(map(float, state["encoder"])),
                tuple(map(float, state["direction"])),
                tuple(map(float, state["repeatability"])),
            )
            sample, moves, draws = int(state["sample"]), int(state["moves"]), int(state["draws"])
            hot = state.get("overheat")
            overheat = None if hot is None else (str(hot[0]), float(hot[1]), float(hot[2]))
        except (TypeError, KeyError, ValueError) as exc:
            raise ValueError(f"not a snapshot of a simulated instrument: {exc}") from None
        if self.clock.now() > time_s:
            raise ValueError(f"the clock is already past {time_s} s")
        self.clock.advance_to(time_s)
        self.bus.restore(motors)
        self.bus.set_moves(sample, moves)
        self.detector.set_draws(sample, draws)
        self.bus.set_overheat(overheat)

    # -- a whole plan ------------------------------------------------------------------
    def run(
        self, plan: Plan, *, start: int = 0, stop: int | None = None, prepare: bool = True
    ) -> SimRun:
        """Measure targets ``start``…``stop`` of ``plan`` one by one (stream index =
        target index, so a run resumed at ``start`` equals the tail of a full run once
        the motors are where the full run had them). With ``prepare`` the detector first
        computes the optics at the poses the plan will reach, vectorized
        (`SimDetector.prepare`); the readings are the same either way."""
        stop = len(plan) if stop is None else stop
        if prepare:
            _, expected, _ = planned_poses(self.rig, plan.angles, self.scene, self.streams)
            self.detector.prepare(expected[start:stop])
        axes, settle = self.rig.axes, self.rig.spec.settle_s
        rows = [
            measure_target(
                self._devices, i, dict(zip(axes, plan.angles[i].tolist(), strict=True)),
                float(plan.exposure_s[i]), int(plan.averages[i]), settle_s=settle,
            )
            for i in range(start, stop)
        ]  # fmt: skip
        n = len(axes)
        true = np.array([[m.true[a] for a in axes] for m in rows if m.true], dtype=np.float64)
        true = true.reshape(-1, n)  # every row has its true pose: this backend is simulated
        wi, wo = self.rig.forward(true)
        return SimRun(
            index=np.arange(start, stop, dtype=np.int64),
            commanded=plan.angles[start:stop],
            read_back=np.array(
                [[m.read_back[a] for a in axes] for m in rows], dtype=np.float64
            ).reshape(-1, n),
            true=true,
            wi=wi,
            wo=wo,
            exposure_s=plan.exposure_s[start:stop],
            averages=plan.averages[start:stop],
            settled_s=np.array([m.settled_s for m in rows], dtype=np.float64),
            end_s=np.array([m.reading.ended_s for m in rows], dtype=np.float64),
            value=np.array([m.reading.value for m in rows], dtype=np.float64),
            std=np.array([m.reading.std for m in rows], dtype=np.float64),
            saturated=np.array([m.reading.saturated for m in rows], dtype=np.bool_),
        )


def emulated_bus(rig: Rig, clock: TimeSource, *, wire_time: bool = False) -> DxlEmulator:
    """A (not yet started) byte-level emulator of the rig's motors, at home, in their
    operating modes, at the rig's bus rate; as fast as the host reads, or with
    ``wire_time`` as a real bus (bytes on the wire and the motors' return delays)."""
    axes = rig.bus_axes()
    emulator = DxlEmulator(
        ids=[a.motor_id for a in axes],
        baud=rig.spec.bus.baud,
        clock=clock,
        wire_time=wire_time,
        return_delay=wire_time,
    )
    for axis, home in zip(axes, rig.home, strict=True):
        motor = emulator.motors[axis.motor_id]
        motor.set("operating_mode", axis.operating_mode)
        motor.set("present_position", axis.to_ticks(float(home)))
    return emulator
