"""Emulated laboratory instruments on pseudo-terminals, each speaking its own command
set as PyMeasure's class sends it, so that `drivers.pymeasure.detector.PyMeasureDetector`
drives the unmodified PyMeasure class over PyVISA's pure-Python backend (resource
``ASRL/dev/pts/N::INSTR``) with no hardware: the SR830 and SR860 lock-in amplifiers
(`sim.peers.visa_instruments.sr830`, `sim.peers.visa_instruments.sr860`), the PM100USB power meter
(`sim.peers.visa_instruments.pm100usb`), the 6517B electrometer and the 2000 multimeter
(`sim.peers.visa_instruments.keithley`). Their readings come from a signal (in a rehearsal:
the simulated detector chain). Each answers every query its class sends for every
setting the class controls, stores what is set and reads it back; a command it does not
know is refused as the instrument documents (`sim.peers.visa_instruments.registers`), never
answered with silence alone. `EMULATORS` maps a PyMeasure class's dotted name to its
emulator.
"""

from sim.peers.visa_instruments.base import EmulatedInstrument, Signal
from sim.peers.visa_instruments.keithley import Keithley2000, Keithley6517B
from sim.peers.visa_instruments.pm100usb import PM100USB
from sim.peers.visa_instruments.sr830 import SR830
from sim.peers.visa_instruments.sr860 import SR860

#: The emulator of each PyMeasure class (dotted name), with the terminator of its
#: answers (what the rig file's ``read_termination`` must say).
EMULATORS: dict[str, type[EmulatedInstrument]] = {
    "pymeasure.instruments.srs.SR830": SR830,
    "pymeasure.instruments.srs.SR860": SR860,
    "pymeasure.instruments.thorlabs.ThorlabsPM100USB": PM100USB,
    "pymeasure.instruments.keithley.Keithley6517B": Keithley6517B,
    "pymeasure.instruments.keithley.Keithley2000": Keithley2000,
}

#: Each emulator's full range at its defaults, in its unit (a rehearsal scales the
#: simulated sensor's full scale to it): the SR830's 1 V sensitivity, the power
#: sensor's 50 mW, the 6517B's 2 µA range and the 2000's 10 V range.
FULL_SCALE: dict[str, float] = {
    "pymeasure.instruments.srs.SR830": 1.0,
    "pymeasure.instruments.srs.SR860": 1.0,
    "pymeasure.instruments.thorlabs.ThorlabsPM100USB": 0.05,
    "pymeasure.instruments.keithley.Keithley6517B": 2e-6,
    "pymeasure.instruments.keithley.Keithley2000": 10.0,
}

__all__ = [
    "EMULATORS",
    "FULL_SCALE",
    "PM100USB",
    "SR830",
    "SR860",
    "EmulatedInstrument",
    "Keithley2000",
    "Keithley6517B",
    "Signal",
]
