"""Keithley 6517B electrometer and Keithley 2000 multimeter, their SCPI dialects as
PyMeasure's ``Keithley6517B`` and ``Keithley2000`` send them. Answers end with a line
feed.

- 6517B: ``:SENS:FUNC 'CURR'``, ``:SENS:CURR:NPLC n`` / ``?``, ``:SENS:CURR:RANG r`` /
  ``?``, ``:SENS:CURR:RANG:AUTO 0|1``, ``:READ?`` and ``:MEAS?`` (``+1.234567E-09NADC,
  +0000012.345secs,+00000rdng#``, after n / 50 s; ``:MEAS?`` keeps the settings, which
  a real one resets), ``SYST:ERR?``, ``*IDN?``, ``*CLS``;
- 2000: ``:CONF:VOLT:DC`` / ``:CONF?``, ``:SENS:VOLT:NPLC n`` / ``?``,
  ``:SENS:VOLT:RANG r`` / ``?``, ``:SENS:VOLT:RANG:AUTO 0|1``, ``:READ?`` (the volts,
  after n / 50 s), ``*IDN?``, ``*CLS``.

Auto-ranging picks the smallest range the reading fits (with 5 % over-range); a
reading beyond 105 % of a fixed range is the over-range value ``+9.9E37``.
"""

from __future__ import annotations

from sim.visa_instruments.base import EmulatedInstrument, Signal

LINE_HZ = 50.0
OVERFLOW = 9.9e37
CURRENT_RANGES = (2e-12, 20e-12, 200e-12, 2e-9, 20e-9, 200e-9, 2e-6, 20e-6, 200e-6, 2e-3, 20e-3)
VOLTAGE_RANGES = (0.1, 1.0, 10.0, 100.0, 1000.0)


class _Meter(EmulatedInstrument):
    quantity = "CURR"
    ranges: tuple[float, ...] = CURRENT_RANGES

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.nplc = 1.0
        self.auto = True
        self.range = self.ranges[-1]

    def _read(self) -> tuple[float, float]:
        integration = self.nplc / LINE_HZ
        value = self.read_signal(integration)
        if self.auto:
            self.range = next((r for r in self.ranges if abs(value) <= r), self.ranges[-1])
        if abs(value) > 1.05 * self.range:
            value = OVERFLOW
        return value, integration

    def _sense(self, c: str) -> tuple[str | None, float] | None:
        q = self.quantity
        if c == f":SENS:{q}:NPLC?":
            return f"{self.nplc:g}", 0.0
        if c.startswith(f":SENS:{q}:NPLC "):
            nplc = float(c.split()[1])
            if not 0.01 <= nplc <= 10:
                raise ValueError(c)
            self.nplc = nplc
            return None, 0.0
        if c == f":SENS:{q}:RANG?":
            return f"{self.range:.6E}", 0.0
        if c.startswith(f":SENS:{q}:RANG:AUTO "):
            self.auto = c.split()[1] in ("1", "ON")
            return None, 0.0
        if c.startswith(f":SENS:{q}:RANG "):
            wanted = abs(float(c.split()[1]))
            self.range = next((r for r in self.ranges if wanted <= r), self.ranges[-1])
            self.auto = False
            return None, 0.0
        if c == "*CLS":
            return None, 0.0
        if c == "*IDN?":
            return self.identity, 0.0
        return None


class Keithley6517B(_Meter):
    """A 6517B measuring current on a pty (module docstring)."""

    identity = "KEITHLEY INSTRUMENTS INC.,MODEL 6517B,4000000,A13/700X"

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.readings = 0

    def answer(self, command: str) -> tuple[str | None, float]:
        c = command.upper()
        sensed = self._sense(c)
        if sensed is not None:
            return sensed
        if c.startswith(":SENS:FUNC"):
            return None, 0.0
        if c in ("SYST:ERR?", ":SYST:ERR?"):
            return '0,"No error"', 0.0
        if c in (":MEAS?", ":READ?"):
            value, integration = self._read()
            self.readings += 1
            return (
                f"{value:+.6E}NADC,+{self.readings * 0.1:011.3f}secs,+{self.readings:05d}rdng#",
                (integration),
            )
        raise ValueError(command)


class Keithley2000(_Meter):
    """A 2000 measuring DC volts on a pty (module docstring)."""

    identity = "KEITHLEY INSTRUMENTS INC.,MODEL 2000,1000000,A20 /A02"
    quantity = "VOLT"
    ranges = VOLTAGE_RANGES

    def answer(self, command: str) -> tuple[str | None, float]:
        c = command.upper()
        sensed = self._sense(c)
        if sensed is not None:
            return sensed
        if c == ":CONF?":
            return '"VOLT:DC"', 0.0
        if c.startswith(":CONF:"):
            return None, 0.0
        if c == ":READ?":
            value, integration = self._read()
            return f"{value:+.8E}", integration
        raise ValueError(command)
