"""Reading lines from the port: `LineIO`, the line-level conversation a
:class:`~drivers.serial_detector.detector.SerialDetector` holds.

Opening and releasing the port, raw reads and writes (an OS error becomes a
:class:`SerialDetectorError` and the detector is told the port was lost), the bounded
line buffer, discarding stale input and resynchronizing after a failed query, and the
errors that quote what was received.
"""

from __future__ import annotations

import contextlib
import logging
import math
import re
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import serial

from drivers.serial_detector.config import SerialDetectorConfig
from drivers.serial_detector.errors import (
    IO_ERRORS,
    OPEN_ERRORS,
    ErrorKind,
    SerialDetectorError,
    SerialDetectorValueError,
    open_reason,
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
class Line:
    """A received line, or (``overflow``) the start of an over-long one."""

    text: str
    overflow: bool = False
    nbytes: int = 0

    def quoted(self) -> str:
        if self.overflow:
            return (
                f"a line longer than {self.nbytes} bytes (max_line_bytes) starting "
                f"{quote(self.text)}"
            )
        return quote(self.text)


def quote(text: str) -> str:
    """``repr`` of a line, truncated: safe to put in a one-line message."""
    if len(text) > _QUOTE_CHARS:
        return repr(text[:_QUOTE_CHARS]) + f"... ({len(text)} characters)"
    return repr(text)


def number(text: str) -> float | None:
    """The float in ``text``, or None if it is not a plain decimal number/nan/inf."""
    text = text.strip()
    if not _NUMBER.fullmatch(text):
        return None
    return float(text)


def pattern(text: str | None) -> re.Pattern[str] | None:
    """``text`` compiled as a regular expression, None for None."""
    return None if text is None else re.compile(text)


class LineIO:
    """The lines exchanged with the device on the port of ``config``.

    It owns the port and what has been received: the line being received, the complete
    lines not yet taken, the bytes of a stale line still being dropped. ``on_reset`` is
    called when a reset banner is seen among discarded lines; ``on_lost`` when an OS
    error has ended the port (after which the port is closed: its owner releases it).
    """

    def __init__(
        self,
        config: SerialDetectorConfig,
        *,
        on_reset: Callable[[], None],
        on_lost: Callable[[], None],
    ) -> None:
        self._config = config
        self._on_reset = on_reset
        self._on_lost = on_lost
        #: The reset banner and the command acknowledgement (None: not configured).
        self.banner = pattern(config.reset_banner)
        self.ack = pattern(config.command_ack)
        self._serial: Any = None
        self._rx = bytearray()  # the line being received
        self._lines: deque[Line] = deque()  # complete lines not yet taken
        self._discarding = 0  # >0: bytes of an over-long/stale line dropped so far
        self._last_rx = -math.inf  # monotonic time of the last byte received
        self._synced_away = 0

    @property
    def port(self) -> str:
        return self._config.port

    @property
    def is_open(self) -> bool:
        return self._serial is not None

    @property
    def synced_away(self) -> int:
        """Lines a resync discarded before its acknowledgement, since it was made."""
        return self._synced_away

    @property
    def pending(self) -> int:
        """Bytes held of the line being received (at most ``max_line_bytes``)."""
        return len(self._rx)

    # -- the port -----------------------------------------------------------------------

    def open(self) -> None:
        """Open the port (`SerialDetectorError` ``open`` if it cannot be), input cleared."""
        cfg = self._config
        try:
            self._serial = serial.serial_for_url(
                cfg.port,
                baudrate=cfg.baud,
                timeout=_POLL_S,
                write_timeout=cfg.timeout_s,
                exclusive=True,
            )
        except OPEN_ERRORS as exc:
            raise self.error(f"cannot open the port: {open_reason(exc)}", "open") from exc
        self.clear()
        log.debug("%s: opened at %d baud", cfg.port, cfg.baud)

    def close(self) -> None:
        """Release the port (idempotent); unsent bytes are dropped, not waited for."""
        port, self._serial = self._serial, None
        self.clear()
        if port is None:
            return
        # A USB serial close() waits up to 30 s for unsent output; drop it instead.
        with contextlib.suppress(Exception):
            port.reset_output_buffer()
        try:
            port.close()
        except Exception as exc:  # nothing more can be done; the fd is gone either way
            log.debug("%s: error while closing: %s", self.port, exc)
        log.debug("%s: closed", self.port)

    # -- input housekeeping -----------------------------------------------------------

    def settle(self) -> None:
        """After opening: wait for the reset banner, or ``settle_s`` without one."""
        settle = self._config.settle_s
        if settle <= 0:
            return
        deadline = time.monotonic() + settle
        while (line := self.next_line(deadline)) is not None:
            if self.banner is not None and not line.overflow and self.banner.search(line.text):
                log.debug("%s: device ready: %s", self.port, line.quoted())
                self.clear()
                return
            log.debug("%s: discarding %s while settling", self.port, line.quoted())
        self.clear()

    def drain(self) -> None:
        """Discard stale input before a query, noticing a reset banner among it."""
        budget = _DRAIN_MAX_BYTES
        while budget > 0:
            waiting = self.in_waiting()
            if not waiting:
                break
            data = self._read(min(waiting, budget, _CHUNK))
            budget -= len(data)
            self._last_rx = time.monotonic()
            self._feed(data)
        self._discard_buffered()

    def resync(self, command: str | None) -> None:
        """After a failed query: make sure a late answer to it is not taken for the
        answer to the next one. With ``command`` (acknowledged: `_sync`) its
        acknowledgement marks the end of everything owed; else discard input until the
        line has been quiet for ``timeout_s`` (at most ``3 × timeout_s``)."""
        if self._sync(command):
            return
        quiet = self._config.timeout_s
        start = time.monotonic()
        quiet_until, give_up = start + quiet, start + 3 * quiet
        while time.monotonic() < min(quiet_until, give_up):
            if self.receive():
                quiet_until = time.monotonic() + quiet
        self._discard_buffered()
        self.clear()

    def _sync(self, command: str | None) -> bool:
        """Send ``command`` (the exposure command last sent, else the first ``init``
        command) and discard every line before its acknowledgement: the device answers
        in order, so nothing owed comes after it. The command goes out again after each
        ``timeout_s`` without one (a line without an ending swallows the acknowledgement
        behind it), three times at most. False without ``command_ack`` or a command;
        `SerialDetectorError` (``timeout``) if no acknowledgement comes (the resync is
        then still needed; a stray acknowledgement later is skipped as an echo is)."""
        cfg = self._config
        if self.ack is None or command is None:
            return False
        for _ in range(3):
            self.send(command)
            deadline = time.monotonic() + cfg.timeout_s
            while (line := self.next_line(deadline)) is not None:
                if line.overflow or line.text == command.strip():
                    continue
                if self.ack.search(line.text):
                    self._discard_buffered()
                    self.clear()
                    return True
                if self.banner is not None and self.banner.search(line.text):
                    self._on_reset()  # re-initialized before the next query
                self._synced_away += 1
                log.debug("%s: resync: discarding %s", self.port, line.quoted())
        budget = 3 * cfg.timeout_s
        raise self.timeout(command, budget, "acknowledgement (resynchronizing)")

    def _discard_buffered(self) -> None:
        while self._lines:
            line = self._lines.popleft()
            if self.banner is not None and not line.overflow and self.banner.search(line.text):
                log.warning(
                    "%s: the device reset between readings (%s); re-initializing",
                    self.port,
                    line.quoted(),
                )
                self._on_reset()
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

    def clear(self) -> None:
        """Forget what has been received."""
        self._rx.clear()
        self._lines.clear()
        self._discarding = 0

    def next_line(self, deadline: float) -> Line | None:
        """The next received line, or None once ``deadline`` (monotonic) has passed."""
        while not self._lines:
            if time.monotonic() >= deadline:
                return None
            self.receive()
        return self._lines.popleft()

    def take_lines(self) -> list[Line]:
        """Every complete line received and not yet taken, in order."""
        lines = list(self._lines)
        self._lines.clear()
        return lines

    def receive(self) -> int:
        """Read what has arrived (waiting at most the poll interval); returns the count."""
        data = self._read(1)
        if data:
            waiting = self.in_waiting()
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
                self._lines.append(Line(preview, overflow=True, nbytes=limit))
                self._discarding = 0 if complete else received
                self._rx.clear()
                continue
            self._rx += part
            if complete:
                text = self._rx.decode("ascii", "replace").strip()
                self._rx.clear()
                if text:
                    log.debug("%s: <- %r", self.port, text)
                    self._lines.append(Line(text))

    # -- raw I/O (every OS error becomes a SerialDetectorError; the port is lost)

    def _port(self) -> Any:
        if self._serial is None:  # pragma: no cover - guarded by measure()
            raise self.error("the port is not open", "closed")
        return self._serial

    def send(self, command: str) -> None:
        """Write ``command`` and the line ending."""
        data = (command + self._config.line_ending).encode("ascii")
        log.debug("%s: -> %r", self.port, command)
        try:
            self._port().write(data)
        except serial.SerialTimeoutException as exc:
            raise self._lost(
                f"writing {command!r} timed out after {self._config.timeout_s} s "
                f"(the device does not take input: flow control, a hung USB adapter?)",
                exc,
            ) from exc
        except IO_ERRORS as exc:
            raise self._lost(f"writing {command!r} failed", exc) from exc

    def _read(self, size: int) -> bytes:
        try:
            return bytes(self._port().read(size))
        except IO_ERRORS as exc:
            raise self._lost("reading failed", exc) from exc

    def in_waiting(self) -> int:
        """Bytes received and not yet read."""
        try:
            return int(self._port().in_waiting)
        except IO_ERRORS as exc:
            raise self._lost("reading failed", exc) from exc

    # -- errors ---------------------------------------------------------------------

    def error(self, what: str, kind: ErrorKind, line: str | None = None) -> SerialDetectorError:
        """A failure of ``kind``, its message naming the port."""
        return SerialDetectorError(
            f"serial detector {self.port}: {what}", port=self.port, kind=kind, line=line
        )

    def invalid(self, what: str) -> SerialDetectorValueError:
        """A bad argument (nothing was sent)."""
        return SerialDetectorValueError(
            f"serial detector {self.port}: {what}", port=self.port, kind="invalid"
        )

    def _lost(self, what: str, exc: BaseException) -> SerialDetectorError:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        self._on_lost()
        return self.error(
            f"{what}: {reason}; the port was released and will be reopened on the next call",
            "io",
        )

    def timeout(
        self, command: str, budget_s: float, what: str, earlier: str = ""
    ) -> SerialDetectorError:
        """No ``what`` to ``command`` within ``budget_s`` (s), quoting a partial line."""
        pending = len(self._rx) or self._discarding
        detail = f" ({earlier})" if earlier else ""
        if pending:
            start = self._rx[:_QUOTE_CHARS].decode("ascii", "replace")
            detail += f"; received {pending} bytes without a line ending" + (
                f" starting {start!r}" if start else ""
            )
        return self.error(
            f"no {what} to {command!r} within {budget_s:.3g} s{detail} (is the device on, "
            f"at {self._config.baud} baud, speaking this protocol?)",
            "timeout",
        )

    def malformed(
        self, command: str, lines: list[Line], expected: str = "a valid answer"
    ) -> SerialDetectorError:
        """``lines`` received instead of ``expected``, quoting the last."""
        last = lines[-1]
        kind: ErrorKind = "overflow" if last.overflow else "malformed"
        return self.error(
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
