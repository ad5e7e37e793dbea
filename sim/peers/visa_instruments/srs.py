"""The Stanford Research Systems dialect the SR830 and SR860 share: a command is a
mnemonic of letters, ``?`` for a query, then parameters separated by commas (spaces
ignored): ``SENS 10``, ``SENS10``, ``AUXV?1``, ``PSTF 0, 1e3``. `SrsInstrument` keeps
a table of settings (`registers.Number` each, some indexed: ``AUXV i, x``), stores
what is set and answers what is asked; an unknown mnemonic or a parameter beyond its
range is refused and sets the standard event status (``*ESR?``: bit 5 a command
error, bit 4 an execution error), as these instruments have no error queue."""

from __future__ import annotations

import re
from collections.abc import Mapping

from sim.peers.visa_instruments.base import EmulatedInstrument
from sim.peers.visa_instruments.registers import (
    MISSING_PARAMETER,
    OUT_OF_RANGE,
    UNDEFINED_HEADER,
    Number,
    Refused,
)

_COMMAND = re.compile(r"\s*(\*?[A-Za-z]+)\s*(\?)?(.*)")


def srs_split(command: str) -> tuple[str, bool, list[str]]:
    """(the mnemonic in capitals, whether it is a query, the parameters)."""
    match = _COMMAND.fullmatch(command)
    if match is None:
        raise Refused(UNDEFINED_HEADER, command)
    name, query, rest = match.groups()
    args = [a.strip() for a in rest.replace(" ", "").split(",")] if rest.strip() else []
    return name.upper(), query is not None, args


class SrsInstrument(EmulatedInstrument):
    """An SRS lock-in's settings on a pty (module docstring). ``settings``: each
    mnemonic's `Number`; ``indexed``: the indices of those that take one first."""

    settings: Mapping[str, Number] = {}
    indexed: Mapping[str, tuple[int, ...]] = {}

    def reset(self) -> None:
        """``*RST``: every setting at its reset value."""
        self.values: dict[tuple[str, int], float] = {}
        for name, number in self.settings.items():
            for index in self.indexed.get(name, (0,)):
                self.values[name, index] = number.default

    def answer(self, command: str) -> tuple[str | None, float]:
        name, is_query, args = srs_split(command)
        if name == "*IDN" and is_query:
            return self.identity, 0.0
        if name == "*ESR" and is_query:
            return self.status.read_esr(), 0.0
        if name in ("*CLS", "*RST"):
            self.status.clear()
            if name == "*RST":
                self.reset()
            self.cleared()
            return None, 0.0
        number = self.settings.get(name)
        if number is None:
            return self.query(name, is_query, args, command)
        index = 0
        if name in self.indexed:
            if not args:
                raise Refused(MISSING_PARAMETER, command)
            index = self.index(args.pop(0), self.indexed[name], command)
        if is_query:
            return number.show(self.values[name, index]), 0.0
        if len(args) != 1:
            raise Refused(MISSING_PARAMETER, command)
        self.values[name, index] = number.parse(args[0], command)
        return None, 0.0

    @staticmethod
    def index(text: str, allowed: tuple[int, ...], command: str) -> int:
        try:
            index = int(float(text))
        except ValueError:
            raise Refused(OUT_OF_RANGE, command) from None
        if index not in allowed:
            raise Refused(OUT_OF_RANGE, command)
        return index

    def setting(self, name: str, index: int = 0) -> float:
        return self.values[name, index]

    def cleared(self) -> None:
        """``*CLS`` / ``*RST`` was received (a subclass clears its own status too)."""

    def query(
        self, name: str, is_query: bool, args: list[str], command: str
    ) -> tuple[str | None, float]:
        """What the table does not hold: the outputs, the status, the buffer."""
        raise Refused(UNDEFINED_HEADER, command)
