"""The simulated backend: the virtual instrument (`sim.virtual`) and the byte-level peers
on pseudo-terminals (`sim.peers`) over one clock (`sim.clock`); `sim.rehearsal` puts a
rig's hardware path on the peers."""

from sim.virtual import (
    Scene,
    SimDetector,
    SimLightSource,
    SimMotorBus,
    SimulatedInstrument,
    load_scene,
    simulate,
)

__all__ = [
    "Scene",
    "SimDetector",
    "SimLightSource",
    "SimMotorBus",
    "SimulatedInstrument",
    "load_scene",
    "simulate",
]
