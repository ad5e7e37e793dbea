"""The simulated devices: virtual motors (`motors`), a virtual detector and light source
(`detector`), and the factory that builds them as one instrument (`instrument`)."""

from sim.virtual.devices.detector import SimDetector, SimLightSource
from sim.virtual.devices.instrument import SimulatedInstrument
from sim.virtual.devices.motors import SimMotorBus

__all__ = ["SimDetector", "SimLightSource", "SimMotorBus", "SimulatedInstrument"]
