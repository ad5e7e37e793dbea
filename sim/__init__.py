"""The simulated backend: virtual motors and detector, noise effects, a Dynamixel bus emulator."""

from sim.devices import SimDetector, SimLightSource, SimMotorBus, SimulatedInstrument
from sim.scene import Scene, load_scene
from sim.simulate import simulate

__all__ = [
    "Scene",
    "SimDetector",
    "SimLightSource",
    "SimMotorBus",
    "SimulatedInstrument",
    "load_scene",
    "simulate",
]
