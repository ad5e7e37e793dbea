"""The rehearsal backend of `gonio acquire --rehearse`: the hardware path without
hardware. The byte-level Dynamixel emulator runs the rig's motors on a pseudo-terminal
and the real `DynamixelBus` drives it through the unmodified SDK; the detector measures
the scene at the positions the bus reads back; time runs ``speedup`` times faster than
real time (motion profiles, settle dwells and exposures alike)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from drivers.base import StageTarget
from drivers.dynamixel.bus import DynamixelBus
from gonio.acquire.devices import Devices
from gonio.rig.model import Rig
from sim.clock import ScaledClock
from sim.devices.detector import SimDetector, SimLightSource
from sim.devices.instrument import emulated_bus
from sim.physics.streams import Streams
from sim.scene import Scene


class RehearsalSide:
    """The `drivers.base.Simulated` side of a rehearsal: which sample's streams the
    detector uses and what is on the stage (the motors are the emulator's: their true
    angles are their read-back ones; a rehearsal is resumed like hardware, with no
    snapshot)."""

    def __init__(self, bus: DynamixelBus, detector: SimDetector) -> None:
        self.bus = bus
        self.detector = detector

    def begin_sample(self, index: int) -> None:
        self.detector.begin_sample(index)

    def show(self, target: StageTarget) -> None:
        self.detector.show(target)

    def true_positions(self) -> dict[str, float]:
        return self.bus.positions()

    def expect(self, goals: Any, index: Any) -> None:
        pass

    def snapshot(self) -> Any:
        return None

    def restore(self, state: Any) -> None:
        raise NotImplementedError("a rehearsal resumes as hardware does, without a snapshot")


@contextmanager
def rehearsal_devices(
    rig: Rig, scene: Scene, seed: int | None, speedup: float
) -> Iterator[tuple[Devices, ScaledClock]]:
    """The emulator running (stopped on exit) and the unopened `Devices` on it."""
    clock = ScaledClock(speedup)
    emulator = emulated_bus(rig, clock)
    with emulator:
        bus = DynamixelBus(emulator.path, rig.bus_axes(), baud=rig.spec.bus.baud)
        light = SimLightSource()
        detector = SimDetector(
            scene, rig, bus.positions, clock=clock,
            streams=Streams(scene.seed if seed is None else seed), light=light,
        )  # fmt: skip
        side = RehearsalSide(bus, detector)
        yield Devices(bus, detector, clock, light, side), clock
