"""The simulated backend: the virtual instrument (`sim.virtual`) and the byte-level peers
on pseudo-terminals (`sim.peers`) over one clock (`sim.clock`); `sim.rehearsal` puts a
rig's hardware path on the peers.

The names below load with their module when first used (`gonio.faces`): a peer's own
command (``python -m sim.dynamixel.emulator``) loads no virtual instrument (scipy)."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from sim.virtual import SimDetector as SimDetector
    from sim.virtual import SimLightSource as SimLightSource
    from sim.virtual import SimMotorBus as SimMotorBus
    from sim.virtual import SimulatedInstrument as SimulatedInstrument
    from sim.virtual import simulate as simulate

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "SimDetector": "virtual",
    "SimLightSource": "virtual",
    "SimMotorBus": "virtual",
    "SimulatedInstrument": "virtual",
    "simulate": "virtual",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
