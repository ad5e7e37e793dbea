"""The driver: :class:`SerialDetector`, a :class:`drivers.base.Detector` on a line-based
serial protocol (see the package docstring and ``docs/reference/serial_detector.md``)."""

from __future__ import annotations

import contextlib
import logging
import math
import re
import statistics
import time
from collections import deque
from typing import Any

import serial

from drivers.base import Clock, SystemClock
from drivers.devices import Resource
from drivers.serial_detector.config import SerialDetectorConfig, _as_int, _as_real
from drivers.serial_detector.errors import (
    _OPEN_ERRORS,
    SerialDetectorClosed,
    SerialDetectorError,
    _open_reason,
)
from drivers.serial_detector.lines import _POLL_S, _Line, _LineIO, _number, _quote, is_saturated
from drivers.serial_detector.stream import _Streaming
from drivers.values import Reading

log = logging.getLogger("drivers.serial_detector")  # one logger for the package

#: Failures after which nothing more is owed by the device: no resync needed.
_ANSWERED = frozenset({"reset", "device", "value", "invalid"})


class SerialDetector(_Streaming, _LineIO, Resource):
    """A :class:`drivers.base.Detector` on a line-based serial protocol.

    Use it as a context manager (``with SerialDetector(config) as det: det.measure(0.1)``)
    or call :meth:`open` and :meth:`close`. Reading lines from the port, raw I/O and the
    error messages come from :class:`~drivers.serial_detector.lines._LineIO`; with a
    ``stream`` section it also streams (`drivers.stream.StreamingDetector`, from
    :class:`~drivers.serial_detector.stream._Streaming`).

    ``clock`` stamps every reading (real time by default); ``exposure_range_s`` is the
    range the instrument allows (the rig file's), checked before anything is sent.
    """

    def __init__(
        self,
        config: SerialDetectorConfig,
        *,
        clock: Clock | None = None,
        exposure_range_s: tuple[float, float] = (0.0, math.inf),
    ) -> None:
        if not isinstance(config, SerialDetectorConfig):
            raise TypeError(f"config must be a SerialDetectorConfig, got {type(config).__name__}")
        lo, hi = (float(x) for x in exposure_range_s)
        if not 0.0 <= lo <= hi:
            raise ValueError(
                f"exposure_range_s must be [min, max] with 0 ≤ min ≤ max, got {lo}, {hi}"
            )
        self._config = config
        self._clock: Clock = clock or SystemClock()
        self._exposure_range = (lo, hi)
        self._response = re.compile(config.response)
        self._banner = _compile_optional(config.reset_banner)
        self._ack = _compile_optional(config.command_ack)
        self._error_reply = _compile_optional(config.error_reply)
        self._saturated_status = _compile_optional(config.saturated_status)
        self._fields = config.template_fields
        self._serial: Any = None
        self._rx = bytearray()  # the line being received
        self._lines: deque[_Line] = deque()  # complete lines not yet consumed
        self._discarding = 0  # >0: bytes of an over-long/stale line dropped so far
        self._last_rx = -math.inf  # monotonic time of the last byte received
        self._needs_init = False
        self._needs_resync = False
        self._reopen = False  # closed by the driver after an I/O error: reopen on next call
        self._exposure_command: str | None = None  # the last set_exposure sent
        self._resets = 0
        self._synced_away = 0
        self._init_stream_state()

    # -- properties ---------------------------------------------------------------

    @property
    def config(self) -> SerialDetectorConfig:
        return self._config

    @property
    def port(self) -> str:
        return self._config.port

    @property
    def is_open(self) -> bool:
        return self._serial is not None

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return self._exposure_range

    @property
    def resynced_away(self) -> int:
        """Lines a resync after a failed exchange discarded before its acknowledgement
        (late answers among them), since the detector was made."""
        return self._synced_away

    @property
    def resets(self) -> int:
        """How many device resets the driver has noticed since it was created."""
        return self._resets

    def __repr__(self) -> str:
        state = "open" if self.is_open else "closed"
        return f"SerialDetector(port={self.port!r}, {state})"

    # -- open / close -------------------------------------------------------------

    def open(self) -> None:
        """Open the port, wait for the device to settle and send the init commands.

        Does nothing if already open. On any failure the port is closed again.
        """
        if self._serial is not None:
            return
        cfg = self._config
        try:
            self._serial = serial.serial_for_url(
                cfg.port,
                baudrate=cfg.baud,
                timeout=_POLL_S,
                write_timeout=cfg.timeout_s,
                exclusive=True,
            )
        except _OPEN_ERRORS as exc:
            raise self._error(f"cannot open the port: {_open_reason(exc)}", "open") from exc
        self._reopen = False
        self._clear_input_state()
        log.debug("%s: opened at %d baud", cfg.port, cfg.baud)
        try:
            self._settle()
            self._quiet_stream()  # a stream left running (a killed run) is stopped
            self._initialize()
        except BaseException:
            self._release()
            raise

    def close(self) -> None:
        """Release the port (idempotent). Unsent bytes are dropped, not waited for; a
        running stream is stopped first (`stop_stream`)."""
        self._reopen = False
        if self._stream is not None:
            with contextlib.suppress(Exception):  # bounded: 3 × timeout_s at most
                self.stop_stream()
        self._release()

    def _release(self) -> None:
        port, self._serial = self._serial, None
        self._needs_init = False
        self._needs_resync = False
        self._exposure_command = None
        self._stream = None
        self._clear_input_state()
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

    # -- measuring ----------------------------------------------------------------

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose for ``exposure_s`` seconds, ``averages`` times, and return the mean.

        ``std`` is the sample standard deviation (ddof 1; 0 for one sample). With
        ``device_averaging`` it is the device's ``std`` group, or NaN if the device
        does not report one, and ``raw`` holds the device's mean only.
        """
        if self._serial is None and not self._reopen:
            raise SerialDetectorClosed(
                f"serial detector {self.port}: the port is not open (use "
                "`with SerialDetector(config) as det:` or call open() first)",
                port=self.port,
                kind="closed",
            )
        exposure_s, averages = self._check_arguments(exposure_s, averages)
        if self._stream is not None:
            raise self._error("measure() during a stream (stop_stream first)", "streaming")
        if self._serial is None:
            log.info("%s: reopening the port after an I/O error", self.port)
            self.open()
        started = self._clock.now()
        try:
            self._ready()
            self._apply_exposure(exposure_s)
            if self._config.device_averaging:
                reading = self._device_averaged(exposure_s, averages, started)
            else:
                reading = self._host_averaged(exposure_s, averages, started)
        except BaseException as exc:
            answered = isinstance(exc, SerialDetectorError) and exc.kind in _ANSWERED
            if not answered and self._serial is not None:
                # A late answer to the interrupted query may still come (after a timeout,
                # malformed lines, Ctrl-C): listen it out before the next query.
                self._needs_resync = True
            raise
        log.debug("%s: %s", self.port, reading)
        return reading

    def ask(self, command: str) -> str:
        """Send ``command`` (no template fields) and return the first line answered
        within ``timeout_s``, an echo skipped: an identification query (``ID?``,
        ``*IDN?``) or any other one-line exchange. Fails as a query does (``timeout``,
        ``device`` for an error reply, ``reset``); ``streaming`` during a stream."""
        if self._serial is None and not self._reopen:
            raise self._error("the port is not open (use open() first)", "closed")
        if not isinstance(command, str) or not command.strip() or not command.isascii():
            raise self._invalid(f"a command must be a non-empty ASCII string, got {command!r}")
        if "\r" in command or "\n" in command:
            raise self._invalid(f"a command must not contain a line ending, got {command!r}")
        if self._stream is not None:
            raise self._error("ask() during a stream (stop_stream first)", "streaming")
        if self._serial is None:
            self.open()
        try:
            self._ready()
            self._send(command)
            deadline = time.monotonic() + self._config.timeout_s
            while (line := self._next_line(deadline)) is not None:
                self._check_unsolicited(line, command)
                if line.overflow or line.text != command.strip():
                    return line.text
            raise self._timeout(command, self._config.timeout_s, "answer")
        except BaseException as exc:
            answered = isinstance(exc, SerialDetectorError) and exc.kind in _ANSWERED
            if not answered and self._serial is not None:
                self._needs_resync = True
            raise

    def _check_arguments(self, exposure_s: object, averages: object) -> tuple[float, int]:
        exposure, n = _as_real(exposure_s), _as_int(averages)
        if exposure is None or not (0 < exposure < math.inf):
            raise self._invalid(
                f"exposure_s must be a positive finite number of seconds, got {exposure_s!r}"
            )
        lo, hi = self._exposure_range
        if not lo <= exposure <= hi:
            raise self._invalid(
                f"exposure {exposure!r} s is outside the detector's range [{lo:g}, {hi:g}] s"
            )
        if n is None or n < 1:
            raise self._invalid(f"averages must be an integer ≥ 1, got {averages!r}")
        for name, scale, unit in (("exposure_ms", 1e3, "ms"), ("exposure_us", 1e6, "µs")):
            if name in self._fields and round(exposure * scale) < 1:
                raise self._invalid(
                    f"exposure_s={exposure!r} rounds to 0 {unit}, below the resolution "
                    f"of the command templates"
                )
        return exposure, n

    def _integrated(self, exposure_s: float) -> float | None:
        """The exposure the device integrates when the templates round it (s), or None
        when it is the one asked."""
        for name, scale in (("exposure_ms", 1e3), ("exposure_us", 1e6)):
            if name in self._fields and "exposure_s" not in self._fields:
                integrated = round(exposure_s * scale) / scale
                return None if integrated == exposure_s else integrated
        return None

    def _values(self, exposure_s: float, averages: int) -> dict[str, float | int]:
        return {
            "exposure_s": exposure_s,
            "exposure_ms": round(exposure_s * 1e3),
            "exposure_us": round(exposure_s * 1e6),
            "averages": averages,
        }

    def _host_averaged(self, exposure_s: float, averages: int, started: float) -> Reading:
        command = self._config.query.format(**self._values(exposure_s, averages))
        budget = exposure_s + self._config.timeout_s
        samples: list[float] = []
        saturated = False
        for _ in range(averages):
            value, match = self._query(command, budget)
            samples.append(value)
            saturated = saturated or self._is_saturated(value, match)
        std = statistics.stdev(samples) if len(samples) > 1 else 0.0
        return Reading(
            value=statistics.fmean(samples),
            std=std,
            n=len(samples),
            saturated=saturated,
            started_s=started,
            ended_s=self._clock.now(),
            raw=tuple(samples),
            exposure_s=self._integrated(exposure_s),
        )

    def _device_averaged(self, exposure_s: float, averages: int, started: float) -> Reading:
        command = self._config.query.format(**self._values(exposure_s, averages))
        budget = exposure_s * averages + self._config.timeout_s
        value, match = self._query(command, budget)
        std = math.nan
        std_text = match.groupdict().get("std")
        if std_text is not None:
            parsed = _number(std_text)
            if parsed is None or not math.isfinite(parsed) or parsed < 0:
                line = match.string
                raise self._error(
                    f"the device's standard deviation {std_text!r} in {_quote(line)} "
                    f"is not a finite number ≥ 0",
                    "value",
                    line,
                )
            std = parsed
        return Reading(
            value=value,
            std=std,
            n=averages,
            saturated=self._is_saturated(value, match),
            started_s=started,
            ended_s=self._clock.now(),
            raw=(value,),
            exposure_s=self._integrated(exposure_s),
        )

    def _is_saturated(self, value: float, match: re.Match[str]) -> bool:
        return is_saturated(value, match, self._config.full_scale, self._saturated_status)

    # -- the conversation -----------------------------------------------------------

    def _query(self, command: str, budget_s: float) -> tuple[float, re.Match[str]]:
        """Send ``command`` and return the value of the first answer that matches
        ``response``. A malformed line is counted and the driver keeps listening (the
        real answer may follow a stray line); if the deadline passes after a malformed
        line, the query is sent again (at most ``retries`` more times)."""
        cfg = self._config
        malformed: list[_Line] = []
        for attempt in range(cfg.retries + 1):
            if attempt:
                log.warning(
                    "%s: no valid answer to %r after %s; asking again",
                    self.port,
                    command,
                    malformed[-1].quoted(),
                )
                self._drain()
            self._send(command)
            deadline = time.monotonic() + budget_s
            heard = False
            while (line := self._next_line(deadline)) is not None:
                self._check_unsolicited(line, command)
                if not line.overflow:
                    if line.text == command.strip():  # the device echoes commands
                        continue
                    if self._stray_ack(line.text):  # a resync's, sent again
                        continue
                    match = self._response.fullmatch(line.text)
                    if match is not None:
                        value = _number(match.group("value"))
                        if value is not None:
                            if not math.isfinite(value):
                                raise self._error(
                                    f"the device answered a non-finite value "
                                    f"{match.group('value')!r} in {_quote(line.text)} "
                                    f"to {command!r}",
                                    "value",
                                    line.text,
                                )
                            return value, match
                heard = True
                malformed.append(line)
                log.warning("%s: malformed answer to %r: %s", self.port, command, line.quoted())
                if len(malformed) > cfg.retries:
                    raise self._malformed(command, malformed)
            if not malformed:
                raise self._timeout(command, budget_s, "answer")
        if not heard:
            raise self._timeout(
                command,
                budget_s,
                "answer",
                f"after {len(malformed)} malformed line(s), the last {malformed[-1].quoted()}",
            )
        raise self._malformed(command, malformed)

    def _stray_ack(self, text: str) -> bool:
        """An acknowledgement where an answer was awaited: a resync sent its command
        again and the earlier one's came late (never a value)."""
        if self._ack is None or self._ack.search(text) is None:
            return False
        return self._response.fullmatch(text) is None

    def _command(self, command: str) -> None:
        """Send an init or set-exposure command and, with ``command_ack``, wait for it."""
        self._send(command)
        if self._ack is None:
            return
        cfg = self._config
        deadline = time.monotonic() + cfg.timeout_s
        malformed: list[_Line] = []
        while (line := self._next_line(deadline)) is not None:
            self._check_unsolicited(line, command)
            if not line.overflow:
                if line.text == command.strip():
                    continue
                if self._ack.search(line.text):
                    return
            malformed.append(line)
            log.warning("%s: unexpected answer to %r: %s", self.port, command, line.quoted())
            if len(malformed) > cfg.retries:
                raise self._malformed(command, malformed, expected="an acknowledgement")
        raise self._timeout(command, cfg.timeout_s, "acknowledgement")

    def _check_unsolicited(self, line: _Line, command: str) -> None:
        """Raise on a reset banner or an error reply received while waiting."""
        if line.overflow:
            return
        if self._banner is not None and self._banner.search(line.text):
            self._note_reset()
            raise self._error(
                f"device reset during a reading: it printed {_quote(line.text)} while the "
                f"driver waited for the answer to {command!r}; it will be re-initialized on "
                f"the next call",
                "reset",
                line.text,
            )
        if self._error_reply is not None and self._error_reply.search(line.text):
            raise self._error(
                f"the device refused {command!r}: {_quote(line.text)}", "device", line.text
            )

    def _ready(self) -> None:
        """Bring the instrument to a known state before a command: resynchronised after
        a lost exchange, unread input dropped, initialised again after a reset."""
        if self._needs_resync:
            self._resync()
        self._drain()
        if self._needs_init:
            self._initialize()

    def _initialize(self) -> None:
        self._needs_init = True
        self._exposure_command = None
        for command in self._config.init:
            self._command(command)
        self._needs_init = False

    def _apply_exposure(self, exposure_s: float) -> None:
        template = self._config.set_exposure
        if template is None:
            return
        command = template.format(**self._values(exposure_s, 1))
        if command == self._exposure_command:
            return
        self._exposure_command = None
        self._command(command)
        self._exposure_command = command

    def _note_reset(self) -> None:
        self._resets += 1
        self._needs_init = True
        self._exposure_command = None


def _compile_optional(pattern: str | None) -> re.Pattern[str] | None:
    return None if pattern is None else re.compile(pattern)
