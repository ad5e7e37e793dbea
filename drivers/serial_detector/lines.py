"""Reading lines from the port: the line-level half of
:class:`~drivers.serial_detector.detector.SerialDetector`.

Raw reads and writes (an OS error becomes a :class:`SerialDetectorError` and releases the
port), the bounded line buffer, discarding stale input and resynchronizing after a failed
query, and the errors that quote what was received.
"""

from __future__ import annotations

import logging
import re
import time
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import serial

from drivers.serial_detector.config import SerialDetectorConfig
from drivers.serial_detector.errors import (
    _IO_ERRORS,
    ErrorKind,
    SerialDetectorError,
    SerialDetectorValueError,
)

log = logging.getLogger("drivers.serial_detector")  # one logger for the package

_POLL_S = 0.02  # the serial read timeout: how late a deadline may be noticed
_CHUNK = 4096  # bytes read at once
_DRAIN_MAX_BYTES = 65536  # stale input read before a query, at most
_FRESH_S = 0.1  # a partial line younger than this may still be arriving
_EOL = re.compile(rb"[\r\n]")
_NUMBER = re.compile(
    r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf|infinity)", re.IGNORECASE
)
_QUOTE_CHARS = 80


@dataclass(frozen=True)
class _Line:
    """A received line, or (``overflow``) the start of an over-long one."""

    text: str
    overflow: bool = False
    nbytes: int = 0

    def quoted(self) -> str:
        if self.overflow:
            return (
                f"a line longer than {self.nbytes} bytes (max_line_bytes) starting "
                f"{_quote(self.text)}"
            )
        return _quote(self.text)


def _quote(text: str) -> str:
    """``repr`` of a line, truncated: safe to put in a one-line message."""
    if len(text) > _QUOTE_CHARS:
        return repr(text[:_QUOTE_CHARS]) + f"... ({len(text)} characters)"
    return repr(text)


def _number(text: str) -> float | None:
    """The float in ``text``, or None if it is not a plain decimal number/nan/inf."""
    text = text.strip()
    if not _NUMBER.fullmatch(text):
        return None
    return float(text)


class _LineIO:
    """A mixin holding :class:`SerialDetector`'s line-level methods.

    Its state is created by ``SerialDetector.__init__``; the attributes and methods it
    uses from there are declared here.
    """

    _config: SerialDetectorConfig
    _banner: re.Pattern[str] | None
    _serial: Any
    _rx: bytearray
    _lines: deque[_Line]
    _discarding: int
    _last_rx: float
    _needs_resync: bool
    _reopen: bool
    _ack: re.Pattern[str] | None
    _exposure_command: str | None
    #: Lines a resync discarded before its acknowledgement.
    _synced_away: int

    if TYPE_CHECKING:

        @property
        def port(self) -> str: ...

        def _note_reset(self) -> None: ...

        def _release(self) -> None: ...

    # -- input housekeeping -----------------------------------------------------------

    def _settle(self) -> None:
        """After opening: wait for the reset banner, or ``settle_s`` without one."""
        settle = self._config.settle_s
        if settle <= 0:
            return
        deadline = time.monotonic() + settle
        while (line := self._next_line(deadline)) is not None:
            if self._banner is not None and not line.overflow and self._banner.search(line.text):
                log.debug("%s: device ready: %s", self.port, line.quoted())
                self._clear_input_state()
                return
            log.debug("%s: discarding %s while settling", self.port, line.quoted())
        self._clear_input_state()

    def _drain(self) -> None:
        """Discard stale input before a query, noticing a reset banner among it."""
        budget = _DRAIN_MAX_BYTES
        while budget > 0:
            waiting = self._in_waiting()
            if not waiting:
                break
            data = self._read(min(waiting, budget, _CHUNK))
            budget -= len(data)
            self._last_rx = time.monotonic()
            self._feed(data)
        self._discard_buffered()

    def _resync(self) -> None:
        """After a failed query: make sure a late answer to it is not taken for the
        answer to the next one. With an acknowledged command at hand (`_sync`) its
        acknowledgement marks the end of everything owed; else discard input until the
        line has been quiet for ``timeout_s`` (at most ``3 × timeout_s``)."""
        if self._sync():
            return
        quiet = self._config.timeout_s
        start = time.monotonic()
        quiet_until, give_up = start + quiet, start + 3 * quiet
        while time.monotonic() < min(quiet_until, give_up):
            if self._receive():
                quiet_until = time.monotonic() + quiet
        self._discard_buffered()
        self._clear_input_state()
        self._needs_resync = False

    def _sync(self) -> bool:
        """Send the exposure command last sent (else the first ``init`` command) and
        discard every line before its acknowledgement: the device answers in order, so
        nothing owed comes after it. The command goes out again after each ``timeout_s``
        without one (a line without an ending swallows the acknowledgement behind it),
        three times at most. False without ``command_ack`` or such a command;
        `SerialDetectorError` (``timeout``) if no acknowledgement comes (the resync is
        then still needed; a stray acknowledgement later is skipped as an echo is)."""
        cfg = self._config
        command = self._exposure_command or next(iter(cfg.init), None)
        if self._ack is None or command is None:
            return False
        for _ in range(3):
            self._send(command)
            deadline = time.monotonic() + cfg.timeout_s
            while (line := self._next_line(deadline)) is not None:
                if line.overflow or line.text == command.strip():
                    continue
                if self._ack.search(line.text):
                    self._discard_buffered()
                    self._clear_input_state()
                    self._needs_resync = False
                    return True
                if self._banner is not None and self._banner.search(line.text):
                    self._note_reset()  # re-initialized before the next query
                self._synced_away += 1
                log.debug("%s: resync: discarding %s", self.port, line.quoted())
        budget = 3 * cfg.timeout_s
        raise self._timeout(command, budget, "acknowledgement (resynchronizing)")

    def _discard_buffered(self) -> None:
        while self._lines:
            line = self._lines.popleft()
            if self._banner is not None and not line.overflow and self._banner.search(line.text):
                log.warning(
                    "%s: the device reset between readings (%s); re-initializing",
                    self.port,
                    line.quoted(),
                )
                self._note_reset()
            else:
                log.debug("%s: discarding stale %s", self.port, line.quoted())
        if self._rx or self._discarding:
            if time.monotonic() - self._last_rx < _FRESH_S:
                # a stale line still arriving: drop the rest of it too, so that its end
                # is not taken for the answer to the next query
                self._discarding += len(self._rx)
                self._rx.clear()
            else:  # a dead fragment (noise, garbage without a line ending): forget it
                self._rx.clear()
                self._discarding = 0

    def _clear_input_state(self) -> None:
        self._rx.clear()
        self._lines.clear()
        self._discarding = 0

    def _next_line(self, deadline: float) -> _Line | None:
        """The next received line, or None once ``deadline`` (monotonic) has passed."""
        while not self._lines:
            if time.monotonic() >= deadline:
                return None
            self._receive()
        return self._lines.popleft()

    def _receive(self) -> int:
        """Read what has arrived (waiting at most the poll interval); returns the count."""
        data = self._read(1)
        if data:
            waiting = self._in_waiting()
            if waiting:
                data += self._read(min(waiting, _CHUNK))
            self._last_rx = time.monotonic()
            self._feed(data)
        return len(data)

    def _feed(self, data: bytes) -> None:
        limit = self._config.max_line_bytes
        parts = _EOL.split(data)
        for i, part in enumerate(parts):
            complete = i < len(parts) - 1
            if self._discarding:
                self._discarding += len(part)
                if complete:
                    log.debug("%s: dropped %d bytes of one line", self.port, self._discarding)
                    self._discarding = 0
                continue
            if len(self._rx) + len(part) > limit:  # never hold more than `limit` bytes
                received = len(self._rx) + len(part)
                head = (bytes(self._rx) + part[:_QUOTE_CHARS])[:_QUOTE_CHARS]
                preview = head.decode("ascii", "replace")
                self._lines.append(_Line(preview, overflow=True, nbytes=limit))
                self._discarding = 0 if complete else received
                self._rx.clear()
                continue
            self._rx += part
            if complete:
                text = self._rx.decode("ascii", "replace").strip()
                self._rx.clear()
                if text:
                    log.debug("%s: <- %r", self.port, text)
                    self._lines.append(_Line(text))

    # -- raw I/O (every OS error becomes a SerialDetectorError, and the port is released)

    def _port(self) -> Any:
        if self._serial is None:  # pragma: no cover - guarded by measure()
            raise self._error("the port is not open", "closed")
        return self._serial

    def _send(self, command: str) -> None:
        data = (command + self._config.line_ending).encode("ascii")
        log.debug("%s: -> %r", self.port, command)
        try:
            self._port().write(data)
        except serial.SerialTimeoutException as exc:
            raise self._io_error(
                f"writing {command!r} timed out after {self._config.timeout_s} s "
                f"(the device does not take input: flow control, a hung USB adapter?)",
                exc,
            ) from exc
        except _IO_ERRORS as exc:
            raise self._io_error(f"writing {command!r} failed", exc) from exc

    def _read(self, size: int) -> bytes:
        try:
            return bytes(self._port().read(size))
        except _IO_ERRORS as exc:
            raise self._io_error("reading failed", exc) from exc

    def _in_waiting(self) -> int:
        try:
            return int(self._port().in_waiting)
        except _IO_ERRORS as exc:
            raise self._io_error("reading failed", exc) from exc

    # -- errors ---------------------------------------------------------------------

    def _error(self, what: str, kind: ErrorKind, line: str | None = None) -> SerialDetectorError:
        return SerialDetectorError(
            f"serial detector {self.port}: {what}", port=self.port, kind=kind, line=line
        )

    def _invalid(self, what: str) -> SerialDetectorValueError:
        return SerialDetectorValueError(
            f"serial detector {self.port}: {what}", port=self.port, kind="invalid"
        )

    def _io_error(self, what: str, exc: BaseException) -> SerialDetectorError:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        self._release()
        self._reopen = True
        return self._error(
            f"{what}: {reason}; the port was released and will be reopened on the next call",
            "io",
        )

    def _timeout(
        self, command: str, budget_s: float, what: str, earlier: str = ""
    ) -> SerialDetectorError:
        pending = len(self._rx) or self._discarding
        detail = f" ({earlier})" if earlier else ""
        if pending:
            start = self._rx[:_QUOTE_CHARS].decode("ascii", "replace")
            detail += f"; received {pending} bytes without a line ending" + (
                f" starting {start!r}" if start else ""
            )
        return self._error(
            f"no {what} to {command!r} within {budget_s:.3g} s{detail} (is the device on, "
            f"at {self._config.baud} baud, speaking this protocol?)",
            "timeout",
        )

    def _malformed(
        self, command: str, lines: list[_Line], expected: str = "a valid answer"
    ) -> SerialDetectorError:
        last = lines[-1]
        kind: ErrorKind = "overflow" if last.overflow else "malformed"
        return self._error(
            f"{len(lines)} malformed line(s) instead of {expected} to {command!r}, "
            f"the last {last.quoted()}",
            kind,
            last.text,
        )


#: A ``saturated`` group's words that mean "not saturated" (case-insensitive).
_FALSE_WORDS = frozenset({"", "0", "false", "no", "n", "off"})


def is_saturated(
    value: float,
    match: re.Match[str],
    full_scale: float | None,
    saturated_status: re.Pattern[str] | None,
) -> bool:
    """Whether a parsed line says its reading saturated: the value at or above the
    configured ``full_scale``, a ``saturated`` group that is not a false word, or a
    ``status`` group that ``saturated_status`` matches."""
    if full_scale is not None and value >= full_scale:
        return True
    groups = match.groupdict()
    flag = groups.get("saturated")
    if flag is not None and flag.strip().lower() not in _FALSE_WORDS:
        return True
    status = groups.get("status")
    return (
        status is not None
        and saturated_status is not None
        and (saturated_status.search(status) is not None)
    )
