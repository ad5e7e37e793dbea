"""Stanford Research Systems SR830 lock-in amplifier (and, in `sim.peers.visa_instruments.sr860`,
the SR860), its RS-232 dialect as PyMeasure's ``SR830`` sends it
(`sim.peers.visa_instruments.srs`). Every setting the class controls is stored and read
back: ``SENS`` (sensitivity index, 26 = 1 V), ``OFLT`` (time constant index), ``OFSL``,
``SYNC``, ``HARM``, ``ISRC``, ``IGND``, ``ICPL``, ``ILIN``, ``FMOD``, ``RSLP``,
``RMOD``, ``SRAT``, ``SLVL``, ``FREQ``, ``PHAS``, ``AUXV i, x`` and ``DDEF i, j, k``
(``DDEF? i`` answers ``j,k``). Measured: ``OUTP? i`` (1 X, 2 Y, 3 R, 4 θ), ``SNAP?
i, j…``, ``OAUX? i``, ``LIAS?`` (the status byte, cleared when read: bit 0 input, 1
filter, 2 output overload; ``LIAS? i`` one bit), ``ERRS?``, ``SPTS?``; and ``*IDN?``,
``*ESR?``, ``*STB?``, ``*CLS``, ``*RST``. Answers end with a carriage return, as the
SR830's RS-232 answers do.

The output R is the signal's rate over the settle time of the set time constant (10.1 τ
at 24 dB/oct); at or above the sensitivity's full scale it overloads (bit 2) and clips
at 110 % of it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import MappingProxyType

from drivers.pymeasure import SETTLE_TAU
from sim.peers.visa_instruments.base import Signal
from sim.peers.visa_instruments.registers import (
    MISSING_PARAMETER,
    OUT_OF_RANGE,
    UNDEFINED_HEADER,
    Number,
    Refused,
)
from sim.peers.visa_instruments.srs import SrsInstrument

SENSITIVITIES = (
    2e-9, 5e-9, 10e-9, 20e-9, 50e-9, 100e-9, 200e-9, 500e-9, 1e-6, 2e-6, 5e-6, 10e-6,
    20e-6, 50e-6, 100e-6, 200e-6, 500e-6, 1e-3, 2e-3, 5e-3, 10e-3, 20e-3, 50e-3, 100e-3,
    200e-3, 500e-3, 1.0,
)  # fmt: skip
TIME_CONSTANTS = (
    10e-6, 30e-6, 100e-6, 300e-6, 1e-3, 3e-3, 10e-3, 30e-3, 100e-3, 300e-3, 1, 3, 10, 30,
    100, 300, 1e3, 3e3, 10e3, 30e3,
)  # fmt: skip


def choice(default: int, top: int) -> Number:
    """An index setting from 0 to ``top``."""
    return Number(default, 0, top, integer=True, fmt="{:d}")


class LockIn(SrsInstrument):
    """What the SR830 and SR860 share: the outputs of a signal through the set time
    constant, slope and sensitivity. Subclasses give the mnemonics and tables."""

    #: The mnemonic of the sensitivity, its values by index, the time constants by
    #: index, the index of X in ``OUTP? i``.
    scale_command = "SENS"
    sensitivities: tuple[float, ...] = SENSITIVITIES
    time_constants: tuple[float, ...] = TIME_CONSTANTS
    first_output = 1

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None,
        phase_deg: float = 0.0, phase: Callable[[], float] | None = None,
    ) -> None:  # fmt: skip
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.reset()
        self.lia = 0  # the LIA status byte
        self.phase_deg = phase_deg
        self._phase = phase

    @property
    def sensitivity_index(self) -> int:
        return int(self.setting(self.scale_command))

    @property
    def time_constant_index(self) -> int:
        return int(self.setting("OFLT"))

    @property
    def slope_index(self) -> int:
        return int(self.setting("OFSL"))

    @property
    def time_constant_s(self) -> float:
        return float(self.time_constants[self.time_constant_index])

    def cleared(self) -> None:
        self.lia = 0

    def _output(self) -> float:
        settle = SETTLE_TAU[6 * (self.slope_index + 1)] * self.time_constant_s
        value = self.read_signal(settle)
        full_scale = self.sensitivities[self.sensitivity_index]
        if abs(value) >= full_scale:
            self.lia |= 0b100
            value = 1.1 * full_scale
        return value

    def outputs(self) -> tuple[float, float, float, float]:
        """(X, Y, R, θ) now (V, V, V, °)."""
        r = self._output()
        if self._phase is not None:
            self.phase_deg = self._phase()
        theta = math.radians(self.phase_deg)
        return r * math.cos(theta), r * math.sin(theta), r, self.phase_deg

    def snapped(self, which: int, outputs: tuple[float, ...]) -> float:
        """A ``SNAP?`` parameter beyond the four outputs (aux inputs: 0 V)."""
        raise NotImplementedError

    def query(
        self, name: str, is_query: bool, args: list[str], command: str
    ) -> tuple[str | None, float]:
        if not is_query:
            raise Refused(UNDEFINED_HEADER, command)
        first = self.first_output
        if name == "OUTP":
            if len(args) != 1:
                raise Refused(MISSING_PARAMETER, command)
            which = self.index(args[0], tuple(range(first, first + 4)), command) - first
            return f"{self.outputs()[which]:.6e}", 0.0
        if name == "SNAP":
            if not 2 <= len(args) <= 6:
                raise Refused(MISSING_PARAMETER, command)
            outputs = self.outputs()
            values = []
            for arg in args:
                which = self.index(arg, tuple(range(first, first + 17)), command) - first
                values.append(outputs[which] if which < 4 else self.snapped(which, outputs))
            return ",".join(f"{v:.6e}" for v in values), 0.0
        if name == "OAUX":
            if len(args) != 1:
                raise Refused(MISSING_PARAMETER, command)
            self.index(args[0], tuple(range(first, first + 4)), command)
            return "0.000", 0.0  # nothing on the aux inputs
        return self.status_query(name, args, command)

    def status_query(self, name: str, args: list[str], command: str) -> tuple[str | None, float]:
        raise Refused(UNDEFINED_HEADER, command)


class SR830(LockIn):
    """An SR830 on a pty (module docstring); ``phase_deg``: the signal's phase (°), or
    ``phase``: where to read it when asked (a simulated lock-in's last reading's)."""

    identity = "Stanford_Research_Systems,SR830,s/n00000,ver1.07"
    terminator = "\r"
    settings = MappingProxyType(
        {
            "SENS": choice(26, 26),
            "OFLT": choice(8, 19),  # 100 ms
            "OFSL": choice(3, 3),
            "SYNC": choice(0, 1),
            "HARM": Number(1, 1, 19999, integer=True, fmt="{:d}"),
            "ISRC": choice(0, 3),
            "IGND": choice(0, 1),
            "ICPL": choice(0, 1),
            "ILIN": choice(0, 3),
            "FMOD": choice(1, 1),  # internal
            "RSLP": choice(0, 2),
            "RMOD": choice(1, 2),  # normal
            "SRAT": choice(4, 14),  # 1 Hz
            "SLVL": Number(1.0, 0.004, 5.0, fmt="{:.3f}"),
            "FREQ": Number(1000.0, 0.001, 102000.0, fmt="{:.4f}"),
            "PHAS": Number(0.0, -360.0, 729.99, fmt="{:.2f}"),
            "AUXV": Number(0.0, -10.5, 10.5, fmt="{:.3f}"),
        }
    )
    indexed = MappingProxyType({"AUXV": (1, 2, 3, 4)})
    #: What each display shows by default (``DDEF i, j, k``: display j, ratio k).
    displays = MappingProxyType({1: (0, 0), 2: (0, 0)})

    def reset(self) -> None:
        super().reset()
        self.display = dict(self.displays)

    def answer(self, command: str) -> tuple[str | None, float]:
        name = command.strip().upper()
        if name.startswith("DDEF"):  # two values per index: the table holds one
            return self._display(command), 0.0
        return super().answer(command)

    def _display(self, command: str) -> str | None:
        rest = command.strip()[4:].replace(" ", "")
        query = rest.startswith("?")
        args = [a for a in rest.lstrip("?").split(",") if a]
        if not args:
            raise Refused(MISSING_PARAMETER, command)
        index = self.index(args[0], (1, 2), command)
        if query:
            j, k = self.display[index]
            return f"{j},{k}"
        if len(args) != 3:
            raise Refused(MISSING_PARAMETER, command)
        j, k = (self.index(a, (0, 1, 2, 3, 4), command) for a in args[1:])
        if k > 2:
            raise Refused(OUT_OF_RANGE, command)
        self.display[index] = (j, k)
        return None

    def snapped(self, which: int, outputs: tuple[float, ...]) -> float:
        # 5-8: aux inputs 1 to 4 (0 V), 9: the reference frequency, 10/11: the displays
        if which == 8:
            return self.setting("FREQ")
        if which in (9, 10):
            j = self.display[which - 8][0]
            return outputs[which - 9] if j == 0 else 0.0  # X or Y
        return 0.0

    def status_query(self, name: str, args: list[str], command: str) -> tuple[str | None, float]:
        if name == "LIAS":
            if args:
                bit = self.index(args[0], tuple(range(8)), command)
                value = (self.lia >> bit) & 1
                self.lia &= ~(1 << bit)
                return str(value), 0.0
            status, self.lia = self.lia, 0
            return str(status), 0.0
        if name == "ERRS":
            return "0", 0.0  # no hardware error
        if name == "SPTS":
            return "0", 0.0  # nothing stored in the buffer
        if name == "*STB":
            # bit 3: an LIA status bit set; bit 5: an event status bit set
            return str((8 if self.lia else 0) | (32 if self.status.esr else 0)), 0.0
        raise Refused(UNDEFINED_HEADER, command)
