"""The virtual instrument: devices on a virtual clock (`devices`) measuring a scene's
material through the radiometric chain (`physics`), the faults a scene injects
(`faults`) and the same run vectorized (`simulate`)."""

from sim.virtual.devices import SimDetector, SimLightSource, SimMotorBus, SimulatedInstrument
from sim.virtual.simulate import simulate

__all__ = [
    "SimDetector",
    "SimLightSource",
    "SimMotorBus",
    "SimulatedInstrument",
    "simulate",
]
