"""The simulated instrument: virtual motors, detector and light sharing one virtual
clock, one run seed and the scene's injected faults.

`SimulatedInstrument` is the simulated backend as the engine sees it: `devices()` gives
the `drivers.devices.Devices` (the contract), and the instrument itself is
their `drivers.base.Simulated` side (which sample comes next, sample or reference on the
stage, the true joint angles, snapshots for resume). `sim.virtual.simulate.simulate` computes
a whole run vectorized; `tests.support.measure.measure_targets` measures the same
run target by target through the engine's own step.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drivers.base import StageTarget
from drivers.devices import Devices, Resource
from gonio.rig import Rig
from gonio.scene import Scene
from sim.clock import ManualClock
from sim.virtual.devices.detector import SimDetector, SimLightSource
from sim.virtual.devices.motors import MotorState, SimMotorBus
from sim.virtual.devices.position_error import planned_poses
from sim.virtual.faults import FaultInjector
from sim.virtual.physics.streams import Streams


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
            pose_at=self.bus.true_position_at,
            lookahead=True,
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
        and its injected faults do not fire twice) and an injected overheat or supply
        sag in force."""
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
            "overheat": self.bus.faults.overheat,
            "supply_sag": self.bus.faults.supply_sag,
        }

    def restore(self, state: Any) -> None:
        """Continue from a `snapshot`: the clock (which must not be past it), the
        motors, the present sample's counters and an overheat or supply sag in force."""
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
            low = state.get("supply_sag")
            sag = None if low is None else (float(low[0]), float(low[1]))
        except (TypeError, KeyError, ValueError) as exc:
            raise ValueError(f"not a snapshot of a simulated instrument: {exc}") from None
        if self.clock.now() > time_s:
            raise ValueError(f"the clock is already past {time_s} s")
        self.clock.advance_to(time_s)
        self.bus.restore(motors)
        self.bus.set_moves(sample, moves)
        self.detector.set_draws(sample, draws)
        self.bus.faults.overheat = overheat
        self.bus.faults.supply_sag = sag
