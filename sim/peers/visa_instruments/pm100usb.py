"""Thorlabs PM100USB optical power meter with an S120C photodiode sensor, its SCPI
dialect as PyMeasure's ``ThorlabsPM100USB`` sends it (`sim.peers.visa_instruments.scpi`):
``SYST:SENS:IDN?`` (the sensor: a photodiode power sensor whose wavelength is
settable), ``SENS:CORR:WAV`` λ / ``?`` / ``? MIN`` / ``? MAX`` (nm, 400 to 1100, the
S120C's range; the class asks the range before it sets a wavelength),
``SENS:AVER:COUN`` n / ``?`` (samples averaged, about 0.3 ms each), ``MEAS:POW?`` (the
power in W, after its averaging), and the common commands. ``MEAS:ENER?`` is refused
(a photodiode measures no pulse energy; PyMeasure's class asks it only of an energy
sensor). Answers end with a line feed.
"""

from __future__ import annotations

from types import MappingProxyType

from sim.peers.visa_instruments.base import Signal
from sim.peers.visa_instruments.registers import UNDEFINED_HEADER, Number, Refused
from sim.peers.visa_instruments.scpi import ScpiInstrument

#: Seconds per averaged sample.
SAMPLE_S = 3e-4
#: A photodiode power sensor (flags 1 + 16 + 32 + 256: power, response and wavelength
#: settable, temperature sensor).
SENSOR_IDN = "S120C,12345678,01-Jan-2024,1,18,289"
#: The S120C's wavelength range (nm).
WAVELENGTHS_NM = (400.0, 1100.0)

WAVELENGTH = "SENS:CORR:WAV"
AVERAGING = "SENS:AVER:COUN"


class PM100USB(ScpiInstrument):
    """A PM100USB with a photodiode sensor on a pty (module docstring); readings at or
    above ``full_scale_w`` are clipped to it (the sensor's range)."""

    identity = "Thorlabs,PM100USB,P2000000,1.6.0"
    settings = MappingProxyType(
        {
            WAVELENGTH: Number(633.0, *WAVELENGTHS_NM),
            AVERAGING: Number(1, 1, 10_000, integer=True),
        }
    )

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None,
        full_scale_w: float = 0.05,
    ) -> None:  # fmt: skip
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.full_scale_w = full_scale_w

    @property
    def count(self) -> int:
        """Samples averaged per reading."""
        return int(self.values[AVERAGING])

    @property
    def wavelength_nm(self) -> float:
        return self.values[WAVELENGTH]

    def query(
        self, header: str, is_query: bool, args: str, command: str
    ) -> tuple[str | None, float]:
        if is_query and header == "SYST:SENS:IDN":
            return SENSOR_IDN, 0.0
        if is_query and header == "MEAS:POW":
            integration = self.count * SAMPLE_S
            power = min(self.read_signal(integration), self.full_scale_w)
            return f"{power:.6E}", integration
        raise Refused(UNDEFINED_HEADER, command)
