"""Thorlabs PM100USB optical power meter, its SCPI dialect as PyMeasure's
``ThorlabsPM100USB`` sends it: ``SYST:SENSOR:IDN?`` (the sensor: a photodiode power
sensor), ``SENS:AVER:COUN n`` / ``SENS:AVER:COUN?`` (samples averaged, about 0.3 ms
each), ``MEAS:POW?`` (the power in W, after its averaging), ``SENSE:CORR:WAV?`` /
``SENSE:CORR:WAV λ``, ``*IDN?``, ``*CLS``. Answers end with a line feed.
"""

from __future__ import annotations

from sim.visa_instruments.base import EmulatedInstrument, Signal

#: Seconds per averaged sample.
SAMPLE_S = 3e-4
#: A photodiode power sensor (flags 1 + 16 + 32 + 256: power, response and wavelength
#: settable, temperature sensor).
SENSOR_IDN = "S120C,12345678,01-Jan-2024,1,18,289"


class PM100USB(EmulatedInstrument):
    """A PM100USB with a photodiode sensor on a pty (module docstring); readings at or
    above ``full_scale_w`` are clipped to it (the sensor's range)."""

    identity = "Thorlabs,PM100USB,P2000000,1.6.0"

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None,
        full_scale_w: float = 0.05,
    ) -> None:  # fmt: skip
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.count = 1
        self.wavelength_nm = 633.0
        self.full_scale_w = full_scale_w

    def answer(self, command: str) -> tuple[str | None, float]:
        c = command.upper()
        if c == "*IDN?":
            return self.identity, 0.0
        if c == "*CLS":
            return None, 0.0
        if c == "SYST:SENSOR:IDN?":
            return SENSOR_IDN, 0.0
        if c.startswith("SENS:AVER:COUN"):
            rest = c.removeprefix("SENS:AVER:COUN").strip()
            if rest == "?":
                return str(self.count), 0.0
            count = int(rest)
            if not 1 <= count <= 10_000:
                raise ValueError(command)
            self.count = count
            return None, 0.0
        if c in ("SENSE:CORR:WAV?", "SENS:CORR:WAV?"):
            return f"{self.wavelength_nm:g}", 0.0
        if c.startswith(("SENSE:CORR:WAV ", "SENS:CORR:WAV ")):
            self.wavelength_nm = float(c.split()[1])
            return None, 0.0
        if c == "MEAS:POW?":
            integration = self.count * SAMPLE_S
            power = min(self.read_signal(integration), self.full_scale_w)
            return f"{power:.6E}", integration
        raise ValueError(command)
