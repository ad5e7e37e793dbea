"""Keithley 6517B electrometer and Keithley 2000 multimeter, their SCPI dialects as
PyMeasure's ``Keithley6517B`` and ``Keithley2000`` send them
(`sim.peers.visa_instruments.scpi`). Answers end with a line feed.

Each measuring function has its settings under ``:SENS:<function>:``: ``NPLC`` (0.01
to 10), ``RANG`` (a value sets the smallest range that holds it and turns auto-ranging
off), ``RANG:AUTO``, and on the 2000 ``REF``, ``REF:STAT``, ``DIG`` (4 to 7),
``DET:BAND`` (AC: 3, 30 or 300 Hz), ``APER`` and ``THR:VOLT:RANG`` (frequency and
period); every one is stored and read back, ``? MIN`` / ``? MAX`` answer its range.

- 6517B: ``:SENS:FUNC 'CURR'`` (or ``'VOLT'``, ``'RES'``) / ``?``, ``:READ?`` and
  ``:MEAS?`` (``+1.234567E-09NADC,+0000012.345secs,+00000rdng#``; ``NVDC`` for volts,
  ``NOHM`` for ohms; ``:MEAS?`` keeps the settings, which a real one resets),
  ``:MEAS:VOLT?``, the source's ``:SOUR:VOLT[:LEV]``, ``:SOUR:VOLT:RANG[:AUTO]``,
  ``:SOUR:CURR:RLIM`` and ``OUTP``;
- 2000: ``:CONF:<function>`` / ``:CONF?`` (``"VOLT:DC"``), ``:READ?`` (the reading in
  the function's unit), ``:SYST:BEEP:STAT``, ``:TRIG:COUN``, ``:TRIG:SEQ:DEL``;
- both: ``:TRAC:POIN`` and ``:TRAC:DATA?`` (the buffer: the last readings taken, as
  many as its points), ``:FORM:DATA ASCII``.

Each reading integrates NPLC / 50 s (a frequency or period reading its aperture).
Auto-ranging picks the smallest range the reading fits (with 5 % over-range); a reading
beyond 105 % of a fixed range is the over-range value ``+9.9E37``.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from sim.peers.visa_instruments.base import Signal
from sim.peers.visa_instruments.registers import ILLEGAL_VALUE, UNDEFINED_HEADER, Number, Refused
from sim.peers.visa_instruments.scpi import ScpiInstrument

LINE_HZ = 50.0
OVERFLOW = 9.9e37
CURRENT_RANGES = (2e-12, 20e-12, 200e-12, 2e-9, 20e-9, 200e-9, 2e-6, 20e-6, 200e-6, 2e-3, 20e-3)
VOLTAGE_RANGES = (0.1, 1.0, 10.0, 100.0, 1000.0)

_E = "{:.6E}"
_SWITCH = Number(0, 0, 1, integer=True, fmt="{:d}")
_ON = Number(1, 0, 1, integer=True, fmt="{:d}")
_NPLC = Number(1.0, 0.01, 10.0, fmt=_E)
_DIGITS = Number(7, 4, 7, integer=True, fmt="{:d}")


def _ranges(steps: tuple[float, ...]) -> Number:
    """A range setting over ``steps``, at its top range by default."""
    return Number(steps[-1], 0.0, steps[-1], fmt=_E, steps=steps)


def _function(
    name: str, ranges: tuple[float, ...] | None, reference: float | None = None,
    *, nplc: bool = True, extra: dict[str, Number] | None = None,
) -> dict[str, Number]:  # fmt: skip
    """The ``SENS:<name>:`` settings of a measuring function."""
    table: dict[str, Number] = {}
    if nplc:
        table["NPLC"] = _NPLC
    if ranges is not None:
        table["RANG"] = _ranges(ranges)
        table["RANG:AUTO"] = _ON
    if reference is not None:
        lo = 0.0 if name in ("RES", "FRES", "FREQ", "PER") else -reference
        table["REF"] = Number(0.0, lo, reference, fmt=_E)
        table["REF:STAT"] = _SWITCH
        table["DIG"] = _DIGITS
    table |= extra or {}
    return {f"SENS:{name}:{key}": number for key, number in table.items()}


class _Meter(ScpiInstrument):
    """A meter measuring in one of its ``functions`` (``SENS:<function>`` settings)."""

    #: Each function's unit suffix (the 6517B's reading format) and its ranges.
    functions: Mapping[str, tuple[str, tuple[float, ...]]] = MappingProxyType({})
    optional = frozenset({"DC", "LEV", "SEQ", "IMM", "AMPL"})
    #: The function at reset.
    default_function = "CURR"

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        self.function = self.default_function
        super().__init__(signal, speedup=speedup, terminator=terminator)

    def reset(self) -> None:
        super().reset()
        self.function = self.default_function
        self.buffer: list[float] = []

    # The settings of the function measured now.
    @property
    def nplc(self) -> float:
        return self.values.get(f"SENS:{self.function}:NPLC", 1.0)

    @property
    def auto(self) -> bool:
        return bool(self.values.get(f"SENS:{self.function}:RANG:AUTO", 0))

    @property
    def range(self) -> float:
        return self.values[f"SENS:{self.function}:RANG"]

    def changed(self, header: str) -> None:
        if header.endswith(":RANG"):  # a range set fixes it
            self.values[header + ":AUTO"] = 0

    def _buffered(self, header: str, is_query: bool, args: str) -> str | None:
        """``:FORM:DATA ASCII`` and ``:TRAC:DATA?`` (the last ``:TRAC:POIN`` readings),
        or None for another header."""
        if header == "FORM:DATA" and not is_query and args.upper().startswith("ASC"):
            return ""
        if header == "TRAC:DATA" and is_query:
            points = int(self.values["TRAC:POIN"])
            return ",".join(f"{v:+.6E}" for v in self.buffer[-points:]) or "+0.000000E+00"
        return None

    def _read(self) -> tuple[float, float]:
        value, integration = self._measure()
        self.buffer = [*self.buffer[-1023:], value]
        return value, integration

    def _measure(self) -> tuple[float, float]:
        aperture = self.values.get(f"SENS:{self.function}:APER")
        integration = aperture if aperture is not None else self.nplc / LINE_HZ
        value = self.read_signal(integration)
        key = f"SENS:{self.function}:RANG"
        if key not in self.values:
            return value, integration
        ranges = self.functions[self.function][1]
        if self.auto:
            self.values[key] = next((r for r in ranges if abs(value) <= r), ranges[-1])
        if abs(value) > 1.05 * self.values[key]:
            value = OVERFLOW
        return value, integration

    def _select(self, name: str, command: str) -> None:
        function = next((f for f in self.functions if f == name.upper()), None)
        if function is None:
            raise Refused(ILLEGAL_VALUE, command)
        self.function = function


class Keithley6517B(_Meter):
    """A 6517B on a pty, measuring current at reset (module docstring)."""

    identity = "KEITHLEY INSTRUMENTS INC.,MODEL 6517B,4000000,A13/700X"
    functions = MappingProxyType(
        {
            "CURR": ("NADC", CURRENT_RANGES),
            "VOLT": ("NVDC", (2.0, 20.0, 200.0)),
            "RES": ("NOHM", tuple(2 * 10.0**k for k in range(6, 18))),
        }
    )
    settings = MappingProxyType(
        {
            **_function("CURR", CURRENT_RANGES),
            **_function("VOLT", (2.0, 20.0, 200.0)),
            **_function("RES", tuple(2 * 10.0**k for k in range(6, 18))),
            "SOUR:VOLT": Number(0.0, -1000.0, 1000.0, fmt=_E),
            "SOUR:VOLT:RANG": _ranges((100.0, 1000.0)),
            "SOUR:VOLT:RANG:AUTO": _SWITCH,
            "SOUR:CURR:RLIM": _SWITCH,
            "OUTP": _SWITCH,
            "TRAC:POIN": Number(100, 1, 6_875_000, integer=True, fmt="{:d}"),
        }
    )

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.readings = 0

    def query(
        self, header: str, is_query: bool, args: str, command: str
    ) -> tuple[str | None, float]:
        if header == "SENS:FUNC":
            if is_query:
                return f'"{self.function}:DC"' if self.function != "RES" else '"RES"', 0.0
            self._select(args.strip("'\" ").split(":")[0], command)
            return None, 0.0
        buffered = self._buffered(header, is_query, args)
        if buffered is not None:
            return buffered or None, 0.0
        if is_query and header in ("MEAS", "READ", "MEAS:VOLT", "MEAS:CURR", "MEAS:RES"):
            if header.startswith("MEAS:"):
                self._select(header[5:], command)
            value, integration = self._read()
            self.readings += 1
            unit = self.functions[self.function][0]
            elapsed = self.readings * 0.1
            reading = f"{value:+.6E}{unit},+{elapsed:011.3f}secs,+{self.readings:05d}rdng#"
            return reading, integration
        raise Refused(UNDEFINED_HEADER, command)


#: The 2000's functions as ``:CONF:`` names them, with what ``:CONF?`` answers.
_CONFIGURATIONS = {
    "VOLT": "VOLT:DC", "VOLT:AC": "VOLT:AC", "CURR": "CURR:DC", "CURR:AC": "CURR:AC",
    "RES": "RES", "FRES": "FRES", "FREQ": "FREQ", "PER": "PER", "TEMP": "TEMP",
    "DIOD": "DIOD", "CONT": "CONT",
}  # fmt: skip
_RESISTANCES = tuple(10.0**k for k in range(2, 9))
_AC = {"DET:BAND": Number(30.0, 3.0, 300.0, fmt=_E, steps=(3.0, 30.0, 300.0))}
_COUNTER = {
    "THR:VOLT:RANG": _ranges(VOLTAGE_RANGES),
    "APER": Number(1.0, 0.01, 1.0, fmt=_E),
}


class Keithley2000(_Meter):
    """A 2000 on a pty, measuring DC volts at reset (module docstring)."""

    identity = "KEITHLEY INSTRUMENTS INC.,MODEL 2000,1000000,A20 /A02"
    default_function = "VOLT"
    functions = MappingProxyType(
        {
            "VOLT": ("", VOLTAGE_RANGES),
            "VOLT:AC": ("", (0.1, 1.0, 10.0, 100.0, 750.0)),
            "CURR": ("", (0.01, 0.1, 1.0, 3.0)),
            "CURR:AC": ("", (1.0, 3.0)),
            "RES": ("", _RESISTANCES),
            "FRES": ("", _RESISTANCES),
            "FREQ": ("", ()),
            "PER": ("", ()),
            "TEMP": ("", ()),
            "DIOD": ("", ()),
            "CONT": ("", ()),
        }
    )
    settings = MappingProxyType(
        {
            **_function("VOLT", VOLTAGE_RANGES, 1010.0),
            **_function("VOLT:AC", (0.1, 1.0, 10.0, 100.0, 750.0), 757.5, extra=_AC),
            **_function("CURR", (0.01, 0.1, 1.0, 3.0), 3.1),
            **_function("CURR:AC", (1.0, 3.0), 3.1, extra=_AC),
            **_function("RES", _RESISTANCES, 120e6),
            **_function("FRES", _RESISTANCES, 120e6),
            **_function("FREQ", None, 15e6, nplc=False, extra=_COUNTER),
            **_function("PER", None, 1.0, nplc=False, extra=_COUNTER),
            **_function("TEMP", None, 1372.0),
            "SENS:TEMP:REF": Number(0.0, -200.0, 1372.0, fmt=_E),
            "SYST:BEEP:STAT": _ON,
            "TRIG:COUN": Number(1, 1, 9999, integer=True, fmt="{:d}"),
            "TRIG:DEL": Number(0.0, 0.0, 999999.999, fmt=_E),
            "TRAC:POIN": Number(2, 2, 1024, integer=True, fmt="{:d}"),
        }
    )

    def query(
        self, header: str, is_query: bool, args: str, command: str
    ) -> tuple[str | None, float]:
        buffered = self._buffered(header, is_query, args)
        if buffered is not None:
            return buffered or None, 0.0
        if header == "CONF" and is_query:
            return f'"{_CONFIGURATIONS[self.function]}"', 0.0
        if header.startswith("CONF:") and not is_query:
            self._select(header[5:], command)
            return None, 0.0
        if header == "READ" and is_query:
            value, integration = self._read()
            return f"{value:+.8E}", integration
        raise Refused(UNDEFINED_HEADER, command)
