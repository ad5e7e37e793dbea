"""Stanford Research Systems SR830 (and SR860) lock-in amplifiers.

The SR830's RS-232 dialect as PyMeasure's ``SR830`` sends it: ``OUTP?i`` (1 X, 2 Y,
3 R, 4 θ), ``SENS?``/``SENSi`` (sensitivity index, 26 = 1 V), ``OFLT?``/``OFLTi``
(time constant index), ``OFSL?``/``OFSLi``, ``LIAS?`` (the status byte, cleared when
read: bit 0 input, 1 filter, 2 output overload), ``*IDN?``, ``*CLS``. Answers end
with a carriage return, as the SR830's RS-232 answers do. `SR860` speaks the SR860's.

The output R is the signal's rate over the settle time of the set time constant (10.1 τ
at 24 dB/oct); at or above the sensitivity's full scale it overloads (bit 2) and clips
at 110 % of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from drivers.pymeasure.config import SETTLE_TAU
from sim.visa_instruments.base import EmulatedInstrument, Signal

SENSITIVITIES = (
    2e-9, 5e-9, 10e-9, 20e-9, 50e-9, 100e-9, 200e-9, 500e-9, 1e-6, 2e-6, 5e-6, 10e-6,
    20e-6, 50e-6, 100e-6, 200e-6, 500e-6, 1e-3, 2e-3, 5e-3, 10e-3, 20e-3, 50e-3, 100e-3,
    200e-3, 500e-3, 1.0,
)  # fmt: skip
TIME_CONSTANTS = (
    10e-6, 30e-6, 100e-6, 300e-6, 1e-3, 3e-3, 10e-3, 30e-3, 100e-3, 300e-3, 1, 3, 10, 30,
    100, 300, 1e3, 3e3, 10e3, 30e3,
)  # fmt: skip


class SR830(EmulatedInstrument):
    """An SR830 on a pty (module docstring); ``phase_deg``: the signal's phase (°), or
    ``phase``: where to read it when asked (a simulated lock-in's last reading's)."""

    identity = "Stanford_Research_Systems,SR830,s/n00000,ver1.07"
    terminator = "\r"
    #: The sensitivity command, its values by index, the time constants by index, and
    #: the index of X in ``OUTP?i``.
    scale_command = "SENS"
    sensitivities: tuple[float, ...] = SENSITIVITIES
    time_constants: tuple[float, ...] = TIME_CONSTANTS
    first_output = 1

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None,
        phase_deg: float = 0.0, phase: Callable[[], float] | None = None,
    ) -> None:  # fmt: skip
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.sensitivity_index = self.sensitivities.index(1.0)
        self.time_constant_index = self.time_constants.index(0.1)
        self.slope_index = 3
        self.status = 0
        self.phase_deg = phase_deg
        self._phase = phase

    @property
    def time_constant_s(self) -> float:
        return float(self.time_constants[self.time_constant_index])

    def _output(self) -> float:
        settle = SETTLE_TAU[6 * (self.slope_index + 1)] * self.time_constant_s
        value = self.read_signal(settle)
        full_scale = self.sensitivities[self.sensitivity_index]
        if abs(value) >= full_scale:
            self.status |= 0b100
            value = 1.1 * full_scale
        return value

    def answer(self, command: str) -> tuple[str | None, float]:
        c = command.upper().replace(" ", "")
        if c == "*IDN?":
            return self.identity, 0.0
        if c == "*CLS":
            self.status = 0
            return None, 0.0
        if c == "LIAS?":
            status, self.status = self.status, 0
            return str(status), 0.0
        for name, attr, top in (
            (self.scale_command, "sensitivity_index", len(self.sensitivities) - 1),
            ("OFLT", "time_constant_index", len(self.time_constants) - 1),
            ("OFSL", "slope_index", 3),
        ):
            if c == f"{name}?":
                return str(getattr(self, attr)), 0.0
            if c.startswith(name):
                index = int(c[len(name) :])
                if not 0 <= index <= top:
                    raise ValueError(command)
                setattr(self, attr, index)
                return None, 0.0
        if c.startswith("OUTP?"):
            which = int(c[5:]) - self.first_output
            r = self._output()
            if self._phase is not None:
                self.phase_deg = self._phase()
            theta = math.radians(self.phase_deg)
            values = (r * math.cos(theta), r * math.sin(theta), r, self.phase_deg)
            return f"{values[which]:.6e}", 0.0
        raise ValueError(command)


class SR860(SR830):
    """An SR860 on a pty: the SR830's model in the SR860's dialect as PyMeasure's
    ``SR860`` sends it (``SCAL i``, index 0 = 1 V; ``OFLT i`` from 1 µs; ``OUTP? i``
    with 0 = X … 3 = θ; ``OFSL i``), answers ending with a line feed. It has no
    ``LIAS?``: an overload shows only as a reading at the sensitivity's full scale."""

    identity = "Stanford_Research_Systems,SR860,003000,v1.47"
    terminator = "\n"
    scale_command = "SCAL"
    sensitivities = (*reversed(SENSITIVITIES), 1e-9)  # 1 V down to 1 nV
    time_constants = (1e-6, 3e-6, *TIME_CONSTANTS)
    first_output = 0

    def answer(self, command: str) -> tuple[str | None, float]:
        if command.upper().replace(" ", "") == "LIAS?":
            raise ValueError(command)
        return super().answer(command)
