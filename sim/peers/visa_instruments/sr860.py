"""Stanford Research Systems SR860 lock-in amplifier: the SR830's model
(`sim.peers.visa_instruments.sr830.LockIn`) in the SR860's dialect as PyMeasure's ``SR860``
sends it: ``SCAL i`` (index 0 = 1 V), ``OFLT i`` from 1 µs, ``OUTP? i`` with 0 = X …
3 = θ, ``OFSL i``, and every setting the class controls stored and read back
(``PHAS``, ``FREQ``, ``FREQINT``, ``HARM``, ``HARMDUAL``, ``SLVL``, ``TBMODE``,
``REFM``, ``RSRC``, ``RTRG``, ``REFZ``, ``IVMD``, ``ISRC``, ``ICPL``, ``IGND``,
``IRNG``, ``ICUR``, ``SYNC``, ``ADVFILT``, ``PSTF``/``PSTA``/``PSTL i, x``, ``AUXV i,
x``, ``DBLK``, ``DLAY``, ``CDSP i, j``, ``CGRF i, j``, ``GSPD``); measured: ``OUTP?``,
``SNAP?``, ``SNAPD?``, ``OAUX?``, ``TBSTAT?``, ``FREQEXT?``, ``FREQDET?``, ``ILVL?``,
``ENBW?``, ``*STB?``. Answers end with a line feed. It has no ``LIAS?`` (PyMeasure's
class reads none): an overload shows only as a reading at the sensitivity's full
scale."""

from __future__ import annotations

from types import MappingProxyType

from sim.peers.visa_instruments.registers import UNDEFINED_HEADER, Number, Refused
from sim.peers.visa_instruments.sr830 import SENSITIVITIES, TIME_CONSTANTS, LockIn, choice

_FREQUENCY = Number(1000.0, 0.001, 500_000.0, fmt="{:.6e}")
#: The equivalent noise bandwidth of each slope's filter, times τ (6 to 24 dB/oct).
NOISE_BANDWIDTH_TAU = (1 / 4, 1 / 8, 3 / 32, 5 / 64)


class SR860(LockIn):
    """An SR860 on a pty (module docstring)."""

    identity = "Stanford_Research_Systems,SR860,003000,v1.47"
    terminator = "\n"
    scale_command = "SCAL"
    sensitivities = (*reversed(SENSITIVITIES), 1e-9)  # 1 V down to 1 nV
    time_constants = (1e-6, 3e-6, *TIME_CONSTANTS)
    first_output = 0
    settings = MappingProxyType(
        {
            "SCAL": choice(0, 27),
            "OFLT": choice(10, 21),  # 100 ms
            "OFSL": choice(3, 3),
            "SYNC": choice(0, 1),
            "ADVFILT": choice(1, 1),
            "PHAS": Number(0.0, -360.0, 360.0, fmt="{:.7f}"),
            "FREQ": _FREQUENCY,
            "FREQINT": _FREQUENCY,
            "HARM": Number(1, 1, 99, integer=True, fmt="{:d}"),
            "HARMDUAL": Number(1, 1, 99, integer=True, fmt="{:d}"),
            "SLVL": Number(1.0, 0.0, 2.0, fmt="{:.9e}"),
            "TBMODE": choice(0, 1),
            "REFM": choice(0, 1),
            "RSRC": choice(0, 3),
            "RTRG": choice(0, 4),
            "REFZ": choice(1, 1),
            "IVMD": choice(0, 1),
            "ISRC": choice(0, 1),
            "ICPL": choice(0, 1),
            "IGND": choice(0, 1),
            "IRNG": choice(0, 4),
            "ICUR": choice(0, 1),
            "PSTF": _FREQUENCY,
            "PSTA": Number(1.0, 0.0, 2.0, fmt="{:.9e}"),
            "PSTL": Number(0.0, -5.0, 5.0, fmt="{:.3e}"),
            "AUXV": Number(0.0, -10.5, 10.5, fmt="{:.3f}"),
            "DBLK": choice(0, 1),
            "DLAY": choice(0, 5),
            "CDSP": choice(0, 16),
            "CGRF": choice(0, 1),
            "GSPD": choice(0, 16),
        }
    )
    indexed = MappingProxyType(
        dict.fromkeys(("PSTF", "PSTA", "PSTL", "AUXV", "CDSP", "CGRF"), (0, 1, 2, 3))
    )

    def snapped(self, which: int, outputs: tuple[float, ...]) -> float:
        # 4-7 aux inputs, 8/9 noise, 10/11 aux outputs, 12 phase, 13 amplitude,
        # 14 DC level, 15 internal frequency, 16 external frequency
        table = {
            10: self.setting("AUXV", 0), 11: self.setting("AUXV", 1),
            12: self.setting("PHAS"), 13: self.setting("SLVL"), 15: self.setting("FREQINT"),
            16: self.setting("FREQ"),
        }  # fmt: skip
        return table.get(which, 0.0)

    def status_query(self, name: str, args: list[str], command: str) -> tuple[str | None, float]:
        if name == "SNAPD":
            return ",".join(f"{v:.6e}" for v in self.outputs()), 0.0
        if name == "TBSTAT":
            return "1", 0.0  # on its internal timebase
        if name in ("FREQEXT", "FREQDET"):
            return f"{self.setting('FREQ'):.6e}", 0.0
        if name == "ILVL":
            return "2", 0.0  # a signal well within the input range
        if name == "ENBW":
            bandwidth = NOISE_BANDWIDTH_TAU[self.slope_index] / self.time_constant_s
            return f"{bandwidth:.6e}", 0.0
        if name == "*STB":
            return str(32 if self.status.esr else 0), 0.0
        raise Refused(UNDEFINED_HEADER, command)
