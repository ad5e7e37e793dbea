"""What the emulated instruments share beyond the transport: a numeric setting's range
and format (`Number`), the refusal of a command (`Refused`, with its SCPI error number)
and the IEEE 488.2 status an instrument keeps of its refusals (`EventStatus`: the
standard event status register and, for a SCPI instrument, its error queue), and the
SCPI header's short form (`scpi_split`).

A refused command is never answered; it is remembered as the instrument documents: a
SCPI instrument (the Keithleys, the PM100USB) queues the error (``SYST:ERR?`` answers
``-113,"Undefined header"`` for an unknown command, ``-222,"Data out of range"`` for a
value beyond its range) and sets its event status bit; the SR830 and SR860, which have
no error queue, set the bit only (``*ESR?``: bit 5 a command error, bit 4 an
execution error).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

UNDEFINED_HEADER = (-113, "Undefined header")
DATA_TYPE_ERROR = (-104, "Data type error")
MISSING_PARAMETER = (-109, "Missing parameter")
OUT_OF_RANGE = (-222, "Data out of range")
ILLEGAL_VALUE = (-224, "Illegal parameter value")
#: Entries an error queue holds; a further error replaces the last with a queue overflow.
QUEUE_LENGTH = 10
QUEUE_OVERFLOW = (-350, "Queue overflow")


class Refused(Exception):
    """A command the instrument refuses: ``code`` and ``message`` as its error queue
    would hold them (SCPI numbering)."""

    def __init__(self, error: tuple[int, str], command: str = "") -> None:
        super().__init__(f"{error[0]},{error[1]!r}: {command}")
        self.code, self.message = error


class EventStatus:
    """The standard event status register and the error queue of IEEE 488.2 / SCPI."""

    def __init__(self) -> None:
        self.esr = 0
        self.queue: deque[tuple[int, str]] = deque()

    def refuse(self, refused: Refused) -> None:
        """Record a refusal: its ESR bit (command error -1xx: bit 5; execution error
        -2xx: bit 4; device-dependent -3xx: bit 3) and a queue entry."""
        code = refused.code
        self.esr |= 32 if -199 <= code <= -100 else 16 if -299 <= code <= -200 else 8
        if len(self.queue) < QUEUE_LENGTH - 1:
            self.queue.append((code, refused.message))
        elif len(self.queue) == QUEUE_LENGTH - 1:
            self.queue.append(QUEUE_OVERFLOW)

    def next_error(self) -> str:
        """``SYST:ERR?``: the oldest error, removed, or ``0,"No error"``."""
        code, message = self.queue.popleft() if self.queue else (0, "No error")
        return f'{code},"{message}"'

    def read_esr(self) -> str:
        """``*ESR?``: the register, cleared by reading."""
        value, self.esr = self.esr, 0
        return str(value)

    def clear(self) -> None:
        """``*CLS``: the register and the queue emptied."""
        self.esr = 0
        self.queue.clear()


@dataclass(frozen=True)
class Number:
    """A numeric setting: its reset value, its range [``lo``, ``hi``], whether it is an
    integer, its answer's format, and ``steps``: the discrete values a range setting
    takes (a value sets the smallest step at or above its magnitude)."""

    default: float
    lo: float
    hi: float
    integer: bool = False
    fmt: str = "{:g}"
    steps: tuple[float, ...] = ()

    def parse(self, text: str, command: str = "") -> float:
        """The value ``text`` sets (a number, ``MIN``, ``MAX``, ``DEF``, ``ON``/``OFF``
        for a switch); `Refused` beyond the range or not a number."""
        word = text.strip().upper()
        keywords = {"MIN": self.lo, "MINIMUM": self.lo, "MAX": self.hi, "MAXIMUM": self.hi}
        keywords |= {"DEF": self.default, "DEFAULT": self.default}
        if (self.lo, self.hi) == (0, 1):
            keywords |= {"ON": 1.0, "OFF": 0.0}
        if not word:
            raise Refused(MISSING_PARAMETER, command)
        if word in keywords:
            value = float(keywords[word])
        else:
            try:
                value = float(word)
            except ValueError:
                raise Refused(DATA_TYPE_ERROR, command) from None
        if not math.isfinite(value):
            raise Refused(DATA_TYPE_ERROR, command)
        if self.integer:
            if value != round(value):
                raise Refused(DATA_TYPE_ERROR, command)
            value = float(round(value))
        if self.steps:
            fits = [s for s in self.steps if abs(value) <= s * (1 + 1e-9)]
            if not fits:
                raise Refused(OUT_OF_RANGE, command)
            return fits[0]
        if not self.lo <= value <= self.hi:
            raise Refused(OUT_OF_RANGE, command)
        return value

    def show(self, value: float) -> str:
        return self.fmt.format(int(value) if self.integer else value)


def short_form(node: str) -> str:
    """A SCPI keyword's short form: its first four letters, or three when the fourth is
    a vowel (``SENSe`` → ``SENS``, ``WAVelength`` → ``WAV``); a numeric suffix kept."""
    word = node.upper()
    digits = len(word) - len(word.rstrip("0123456789"))
    stem, suffix = (word[:-digits], word[-digits:]) if digits else (word, "")
    if len(stem) > 4:
        stem = stem[:3] if stem[3] in "AEIOU" else stem[:4]
    return stem + suffix


def scpi_split(command: str, optional: frozenset[str] = frozenset()) -> tuple[str, bool, str]:
    """(the header in short form without its leading colon or ``optional`` nodes,
    whether it is a query, the parameters' text): ``:SENSe:CORR:WAV? MIN`` →
    (``SENS:CORR:WAV``, True, ``MIN``)."""
    head, _, rest = command.strip().partition(" ")
    query = head.endswith("?")
    nodes = [short_form(n) for n in head.rstrip("?").lstrip(":").split(":")]
    kept = [n for i, n in enumerate(nodes) if i == 0 or n not in optional]
    return ":".join(kept), query, rest.strip()
