"""The byte-level peers the real drivers talk to on pseudo-terminals: the Dynamixel bus
emulator (`dynamixel`), the serial photometer (`serial_photometer`), the VISA lab
instruments (`visa_instruments`) and the lamp relay (`serial_light`).

Imported by module: a peer started from the command line loads only its own."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from sim.peers import responsive as responsive
    from sim.peers.serial_light import SerialLamp as SerialLamp
    from sim.peers.serial_photometer import STREAM_CONFIG as STREAM_CONFIG
    from sim.peers.serial_photometer import SerialPhotometer as SerialPhotometer
    from sim.peers.serial_photometer.protocol import mismatch as mismatch
    from sim.peers.visa_instruments import EMULATORS as EMULATORS
    from sim.peers.visa_instruments import FULL_SCALE as FULL_SCALE
    from sim.peers.visa_instruments import EmulatedInstrument as EmulatedInstrument
    from sim.peers.visa_instruments.sr830 import SR830 as SR830

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "EMULATORS": "visa_instruments",
    "EmulatedInstrument": "visa_instruments",
    "FULL_SCALE": "visa_instruments",
    "SR830": "visa_instruments.sr830",
    "STREAM_CONFIG": "serial_photometer",
    "SerialLamp": "serial_light",
    "SerialPhotometer": "serial_photometer",
    "mismatch": "serial_photometer.protocol",
    "responsive": "responsive",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
