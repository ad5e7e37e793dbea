"""`ScpiInstrument`: an emulated SCPI instrument whose settings are a table of headers
(`registers.Number` each), so that every setting its PyMeasure class writes is stored
and read back in the instrument's format: ``HEADER value`` sets (a number, ``MIN``,
``MAX``, ``DEF``, ``ON``/``OFF``), ``HEADER?`` answers it and ``HEADER? MIN`` / ``MAX``
its range; the IEEE 488.2 common commands (``*IDN?``, ``*OPC?``, ``*STB?``, ``*OPT?``,
``*ESR?``, ``*CLS``, ``*RST``) and ``SYST:ERR?`` answer as the standard says; any other
header is refused with ``-113,"Undefined header"`` (`sim.peers.visa_instruments.registers`).
Headers are compared in their short form, so ``SENSe:CORRection:WAVelength`` and
``SENS:CORR:WAV`` are one."""

from __future__ import annotations

from collections.abc import Mapping

from sim.peers.visa_instruments.base import EmulatedInstrument, Signal
from sim.peers.visa_instruments.registers import UNDEFINED_HEADER, Number, Refused, scpi_split

#: The status byte's event summary bit (ESB): an enabled event status bit is set.
ESB = 32
#: The status byte's error/event queue bit (EAV): the error queue is not empty.
EAV = 4


class ScpiInstrument(EmulatedInstrument):
    """A SCPI instrument on a pty (module docstring). Subclasses give ``settings`` (the
    table), ``optional`` (header nodes that may be left out, e.g. ``LEVel``),
    ``options`` (``*OPT?``'s answer) and implement `query` for what is measured."""

    settings: Mapping[str, Number] = {}
    optional: frozenset[str] = frozenset()
    options = "0"

    def __init__(
        self, signal: Signal, *, speedup: float = 1.0, terminator: str | None = None
    ) -> None:
        super().__init__(signal, speedup=speedup, terminator=terminator)
        self.values: dict[str, float] = {}
        self.reset()

    def reset(self) -> None:
        """``*RST``: every setting at its reset value."""
        self.values = {header: number.default for header, number in self.settings.items()}

    def answer(self, command: str) -> tuple[str | None, float]:
        header, is_query, args = scpi_split(command, self.optional)
        common = self._common(header, is_query)
        if common is not None:
            return common, 0.0
        if header == "*CLS" or header == "*RST":
            self.status.clear()
            if header == "*RST":
                self.reset()
            return None, 0.0
        number = self.settings.get(header)
        if number is not None:
            if is_query:
                bound = args.upper()[:3]
                if bound in ("MIN", "MAX", "DEF"):
                    return number.show(number.parse(bound, command)), 0.0
                return number.show(self.values[header]), 0.0
            self.values[header] = number.parse(args, command)
            self.changed(header)
            return None, 0.0
        return self.query(header, is_query, args, command)

    def _common(self, header: str, is_query: bool) -> str | None:
        if not is_query:
            return None
        if header == "*IDN":
            return self.identity
        if header == "*OPC":
            return "1"
        if header == "*OPT":
            return self.options
        if header == "*ESR":
            return self.status.read_esr()
        if header == "*STB":
            return str((ESB if self.status.esr else 0) | (EAV if self.status.queue else 0))
        if header == "SYST:ERR":
            return self.status.next_error()
        return None

    def changed(self, header: str) -> None:
        """A setting was written (a subclass follows what depends on it)."""

    def query(
        self, header: str, is_query: bool, args: str, command: str
    ) -> tuple[str | None, float]:
        """What the table does not hold: a measurement or a command with an effect."""
        raise Refused(UNDEFINED_HEADER, command)
