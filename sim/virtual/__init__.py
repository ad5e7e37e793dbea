"""The virtual instrument: devices on a virtual clock (`devices`) measuring a scene's
material through the radiometric chain (`physics`), the faults a scene injects
(`faults`) and the same run vectorized (`simulate`)."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from sim.virtual.devices import SimDetector, SimLightSource, SimMotorBus, SimulatedInstrument
from sim.virtual.simulate import simulate

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from sim.virtual.devices.detector import LightState as LightState
    from sim.virtual.devices.detector import sensor_of as sensor_of
    from sim.virtual.physics.lockin import ENBW_TAU as ENBW_TAU
    from sim.virtual.physics.optics import SceneOptics as SceneOptics
    from sim.virtual.physics.streams import Streams as Streams
    from sim.virtual.record import SimRun as SimRun
    from sim.virtual.simulate import expected_rate as expected_rate

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "ENBW_TAU": "physics.lockin",
    "LightState": "devices.detector",
    "SceneOptics": "physics.optics",
    "SimRun": "record",
    "Streams": "physics.streams",
    "expected_rate": "simulate",
    "sensor_of": "devices.detector",
}
__all__ = [
    "SimDetector",
    "SimLightSource",
    "SimMotorBus",
    "SimulatedInstrument",
    "simulate",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
