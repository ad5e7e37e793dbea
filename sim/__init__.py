"""The simulated backend: the virtual instrument (`sim.virtual`) and the byte-level peers
on pseudo-terminals (`sim.peers`) over one clock (`sim.clock`); `sim.rehearsal` puts a
rig's hardware path on the peers."""

from sim.virtual import (
    SimDetector,
    SimLightSource,
    SimMotorBus,
    SimulatedInstrument,
    simulate,
)

__all__ = [
    "SimDetector",
    "SimLightSource",
    "SimMotorBus",
    "SimulatedInstrument",
    "simulate",
]
