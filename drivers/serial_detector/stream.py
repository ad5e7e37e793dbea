"""The streaming half of :class:`~drivers.serial_detector.detector.SerialDetector`:
``start_stream`` / ``read_stream`` / ``stop_stream`` (`drivers.stream.StreamingDetector`)
for a device configured with a `SerialStreamConfig` (``docs/reference/serial_detector.md``,
"Streaming").

Stamps. Every line is stamped with the host clock when its bytes are read (all lines of
one read share that time, ``received_s``). A window's end on the host clock is

* with a ``device_t`` group: ``device_t + offset``, the offset being the smallest
  ``received − device_t`` seen so far in this stream minus ``latency_s`` (the
  fastest line bounds the latency from above, so the offset converges in a few lines);
* without: ``received − latency_s``, the earlier lines of a read spaced one period
  apart before the last;
* with ``starts_on_command`` (the device's first window begins when the start command
  arrives): within the bounds the start command gives, ``sent + period + (device_t −
  the first line's device_t)`` from below (``sent`` the host clock just before the
  command left) and, with a ``command_ack`` (the device acknowledges the command when
  its first window begins; `start_stream` awaits the first line after it, at most
  ``timeout_s``), the same from the acknowledgement's arrival from above: the
  arrivals' estimate (the upper bounds less ``latency_s``), never below the lower
  bound. A device slow to take the command (its loop busy) starts late; the
  acknowledgement's arrival says how late.

Then ``ended_s`` is raised, if needed, to the previous window's end plus the
integration, so stamps increase and windows never overlap; ``started_s = ended_s −
integration``.
"""

from __future__ import annotations

import contextlib
import math
import re
import string
import time
from collections import deque
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from drivers.base import Clock
from drivers.errors import StreamNotSupported
from drivers.serial_detector.config import SerialDetectorConfig, SerialStreamConfig, _as_real
from drivers.serial_detector.errors import (
    SerialDetectorClosed,
    SerialDetectorError,
    SerialDetectorValueError,
)
from drivers.serial_detector.lines import _Line, _number, _quote, is_saturated
from drivers.serial_detector.trace import StreamTrace
from drivers.stream import StreamReading

#: The shortest quiet (s) after ``stop`` that means the device has stopped.
_QUIET_MIN_S = 0.05


@dataclass
class _Stream:
    """One running stream's state."""

    rate_hz: float
    integration_s: float
    start: str
    last_line: float  # time.monotonic() of the last line (or of the start)
    stall_s: float
    prev_ended: float = -math.inf
    offset_s: float = math.inf  # min(received − device_t) so far
    malformed: list[_Line] = field(default_factory=list)
    pending: deque[tuple[_Line, float]] = field(default_factory=deque)
    lines: int = 0  # data lines received: the clock of a device that sends no time
    sent_s: float = math.nan  # host clock just before the start command was sent
    start_offset_s: float = math.nan  # sent_s + period − the first line's device clock
    ack_offset_s: float = math.inf  # start_ack_s + period − the first line's device clock
    begun: bool = False  # a data line or the start's acknowledgement came
    stopping: bool = False  # ``stop`` was sent
    stopped: bool = False  # ``stop`` was acknowledged (after every data line)
    start_ack_s: float | None = None  # host clock when the start's acknowledgement came
    stop_sent_s: float | None = None  # host clock just before ``stop`` was sent
    stop_ack_s: float | None = None  # host clock when the stop's acknowledgement came
    after_ack: int = 0  # data lines read after the stop's acknowledgement
    longest: int = 0  # the longest data line (bytes, without its line ending)

    @property
    def period_s(self) -> float:
        return 1.0 / self.rate_hz


class _Streaming:
    """A mixin holding :class:`SerialDetector`'s streaming methods (state made by
    ``_init_stream_state``, called from ``SerialDetector.__init__``)."""

    _config: SerialDetectorConfig
    _clock: Clock
    _serial: Any
    _reopen: bool
    _lines: deque[_Line]
    _needs_resync: bool
    _needs_init: bool
    _exposure_range: tuple[float, float]
    _ack: re.Pattern[str] | None
    _saturated_status: re.Pattern[str] | None

    if TYPE_CHECKING:

        @property
        def port(self) -> str: ...

        def open(self) -> None: ...

        def _send(self, command: str) -> None: ...

        def _receive(self) -> int: ...

        def _in_waiting(self) -> int: ...

        def _ready(self) -> None: ...

        def _clear_input_state(self) -> None: ...

        def _check_unsolicited(self, line: _Line, command: str) -> None: ...

        def _error(self, what: str, kind: Any, line: str | None = None) -> SerialDetectorError: ...

        def _invalid(self, what: str) -> SerialDetectorValueError: ...

    def _init_stream_state(self) -> None:
        stream = self._config.stream
        self._stream_line = None if stream is None else re.compile(stream.line)
        self._stream: _Stream | None = None
        self._last_trace: StreamTrace | None = None

    @property
    def can_stream(self) -> bool:
        """Whether the configuration has a streaming mode (`drivers.stream.can_stream`)."""
        return self._config.stream is not None

    @property
    def is_streaming(self) -> bool:
        return self._stream is not None

    @property
    def last_stream(self) -> StreamTrace | None:
        """What the driver saw of the last stream stopped or failed (`StreamTrace`), None
        before the first."""
        return self._last_trace

    def _keep_trace(self, stream: _Stream) -> None:
        self._last_trace = StreamTrace(
            command=stream.start,
            rate_hz=stream.rate_hz,
            integration_s=stream.integration_s,
            sent_s=stream.sent_s,
            start_acknowledged_s=stream.start_ack_s,
            stop_sent_s=stream.stop_sent_s,
            stop_acknowledged_s=stream.stop_ack_s,
            data_lines=stream.lines,
            lines_after_ack=stream.after_ack,
            longest_line_bytes=stream.longest,
        )

    def _stream_config(self) -> SerialStreamConfig:
        if self._config.stream is None:
            raise StreamNotSupported(
                f"serial detector {self.port}: cannot stream: its configuration has no "
                "stream section (start, stop, line; docs/reference/serial_detector.md)"
            )
        return self._config.stream

    # -- start ------------------------------------------------------------------------

    def start_stream(
        self, rate_hz: float | None = None, integration_s: float | None = None
    ) -> None:
        """Start streaming readings of ``integration_s`` s (default: the whole period)
        every ``1 / rate_hz`` s (default: the configuration's ``rate_hz``).

        Refused before anything is sent (`SerialDetectorError`, kind ``invalid``) for a
        rate above ``max_rate_hz``, an integration longer than the period, outside the
        exposure range or below the templates' resolution; ``streaming`` when a stream
        already runs; `StreamNotSupported` without a stream section.
        """
        cfg = self._stream_config()
        if self._serial is None and not self._reopen:
            raise SerialDetectorClosed(
                f"serial detector {self.port}: the port is not open (use "
                "`with SerialDetector(config) as det:` or call open() first)",
                port=self.port,
                kind="closed",
            )
        if self._stream is not None:
            raise self._error("a stream is already running (stop_stream first)", "streaming")
        rate, integration, command = self._stream_arguments(cfg, rate_hz, integration_s)
        if self._serial is None:
            self.open()
        try:
            self._ready()
            sent = self._clock.now()
            self._send(command)
        except BaseException:
            self._needs_resync = self._serial is not None
            raise
        stall = self._config.timeout_s + 2.0 / rate
        stream = _Stream(rate, integration, command, time.monotonic(), stall, sent_s=sent)
        self._stream = stream
        if cfg.starts_on_command and self._ack is not None:
            self._await_first_line(stream)

    def _await_first_line(self, stream: _Stream) -> None:
        """Wait (at most ``timeout_s``) for the first line after the start command, its
        acknowledgement, stamped as it arrives: the bound from above on when the first
        window began (the module docstring). Nothing is parsed here; without a line in
        time, ``read_stream`` finds the stall."""
        give_up = time.monotonic() + self._config.timeout_s
        try:
            while not stream.pending and time.monotonic() < give_up:
                self._pump(stream, block=True)
        except BaseException:
            self._abort_stream()
            raise

    def _stream_arguments(
        self, cfg: SerialStreamConfig, rate_hz: float | None, integration_s: float | None
    ) -> tuple[float, float, str]:
        rate = _as_real(cfg.rate_hz if rate_hz is None else rate_hz)
        if rate is None or not 0 < rate <= cfg.max_rate_hz:
            raise self._invalid(
                f"stream rate_hz must be a number in (0, {cfg.max_rate_hz:g}] Hz "
                f"(stream.max_rate_hz), got {rate_hz!r}"
            )
        period = 1.0 / rate
        integration = _as_real(period if integration_s is None else integration_s)
        if integration is None or not 0 < integration <= period * (1 + 1e-9):
            raise self._invalid(
                f"stream integration_s must be in (0, {period:.6g}] s (the period at "
                f"{rate:g} Hz), got {integration_s!r}"
            )
        lo, hi = self._exposure_range
        if not lo <= integration <= hi:
            raise self._invalid(
                f"stream integration {integration:.6g} s is outside the detector's range "
                f"[{lo:g}, {hi:g}] s"
            )
        fields = {
            "rate_hz": rate,
            "period_ms": round(period * 1e3),
            "period_us": round(period * 1e6),
            "integration_s": integration,
            "integration_ms": round(integration * 1e3),
            "integration_us": round(integration * 1e6),
        }
        names = {n for _, n, _, _ in string.Formatter().parse(cfg.start) if n is not None}
        # The integration the device does when the template rounds it.
        for name, scale in (("integration_ms", 1e3), ("integration_us", 1e6)):
            if name in names and "integration_s" not in names:
                units = round(integration * scale)
                if units / scale > period:  # never round past the period
                    units = math.floor(period * scale)
                if units < 1:
                    raise self._invalid(
                        f"stream integration {integration!r} s rounds to 0 in {{{name}}}"
                    )
                integration = units / scale
                fields[name] = units
                break
        return rate, min(integration, period), cfg.start.format(**fields)

    # -- read -------------------------------------------------------------------------

    def read_stream(self, timeout_s: float = 0.0) -> list[StreamReading]:
        """The readings received since the last call, in order; with none yet, wait up
        to ``timeout_s`` (s) for the first. Raises `SerialDetectorError` naming the port
        when the stream stalls (no line for ``timeout_s`` of the configuration plus two
        periods), on malformed lines beyond ``retries`` in a row, a reset, an error
        reply or a non-finite value; the stream is then stopped (best effort)."""
        stream = self._stream
        if stream is None:
            raise self._error("no stream is running (start_stream first)", "streaming")
        wait_until = time.monotonic() + max(0.0, float(timeout_s))
        try:
            readings: list[StreamReading] = []
            self._pump(stream, block=False)
            while True:
                readings += self._parse_pending(stream)
                if readings or time.monotonic() >= wait_until:
                    break
                self._check_stall(stream)
                self._pump(stream, block=True)
            if not readings:
                self._check_stall(stream)
            return readings
        except BaseException:
            self._abort_stream()
            raise

    def _pump(self, stream: _Stream, *, block: bool) -> None:
        """Receive what has arrived (``block``: waiting at most the poll interval) and
        stamp the new lines with the host clock."""
        if block or self._in_waiting():
            self._receive()
        received = self._clock.now()
        new = list(self._lines)
        self._lines.clear()
        if new:
            stream.last_line = time.monotonic()
        stream.pending.extend((line, received) for line in new)

    def _check_stall(self, stream: _Stream) -> None:
        quiet = time.monotonic() - stream.last_line
        if quiet > stream.stall_s:
            raise self._error(
                f"the stream stopped: no line for {quiet:.3g} s (at {stream.rate_hz:g} Hz, "
                f"after {stream.start!r}; is the device on, speaking this protocol?)",
                "timeout",
            )

    def _parse_pending(self, stream: _Stream) -> list[StreamReading]:
        """Readings from the stamped lines received (data lines only)."""
        cfg = self._stream_config()
        assert self._stream_line is not None
        parsed: list[tuple[float, float, bool, float | None, float, float]] = []
        while stream.pending:
            line, received = stream.pending.popleft()
            self._check_unsolicited(line, stream.start)
            match = None if line.overflow else self._stream_line.fullmatch(line.text)
            if match is None:
                if not line.overflow and self._ack is not None and self._ack.search(line.text):
                    # the start's acknowledgement, or once stopping (and begun) the stop's
                    if stream.stopping and stream.begun:
                        if not stream.stopped:
                            stream.stop_ack_s = received
                        stream.stopped = True
                    elif not stream.begun:
                        stream.start_ack_s = received
                    stream.begun = True
                    continue
                if not line.overflow and line.text in (stream.start.strip(), cfg.stop.strip()):
                    continue  # an echo
                stream.malformed.append(line)
                if len(stream.malformed) > self._config.retries:
                    raise self._error(
                        f"{len(stream.malformed)} malformed stream line(s) in a row after "
                        f"{stream.start!r}, the last {line.quoted()}",
                        "overflow" if line.overflow else "malformed",
                        line.text,
                    )
                continue
            stream.malformed.clear()
            stream.begun = True
            stream.after_ack += stream.stopped
            stream.longest = max(stream.longest, len(line.text))
            value = self._finite(match, "value", line)
            groups = match.groupdict()
            std = math.nan if groups.get("std") is None else self._finite(match, "std", line)
            device_t = None
            if groups.get("device_t") is not None:
                device_t = self._finite(match, "device_t", line) * cfg.device_time_s
                clock = device_t
            else:  # the device's clock is its line count: it streams at a steady rate
                clock = stream.lines * stream.period_s
            if not stream.lines:  # the first window began when the command arrived
                stream.start_offset_s = stream.sent_s + stream.period_s - clock
                if stream.start_ack_s is not None:
                    stream.ack_offset_s = stream.start_ack_s + stream.period_s - clock
            stream.lines += 1
            stream.offset_s = min(stream.offset_s, received - clock)
            parsed.append((value, std, self._saturated(value, match), device_t, received, clock))
        readings = []
        for value, std, saturated, device_t, received, clock in parsed:
            end = clock + stream.offset_s - cfg.latency_s
            if cfg.starts_on_command:  # between the start command's bounds
                end = min(end, clock + stream.ack_offset_s - cfg.latency_s)
                end = max(end, clock + stream.start_offset_s)
            end = max(end, stream.prev_ended + stream.integration_s)
            stream.prev_ended = end
            readings.append(
                StreamReading(
                    value=value,
                    std=std,
                    started_s=end - stream.integration_s,
                    ended_s=end,
                    saturated=saturated,
                    device_t_s=device_t,
                    received_s=received,
                )
            )
        return readings

    def _finite(self, match: re.Match[str], group: str, line: _Line) -> float:
        number = _number(match.group(group))
        if number is None or not math.isfinite(number) or (group == "std" and number < 0):
            raise self._error(
                f"the stream's {group} {match.group(group)!r} in {_quote(line.text)} is not "
                "a finite number" + (" ≥ 0" if group == "std" else ""),
                "value",
                line.text,
            )
        return number

    def _saturated(self, value: float, match: re.Match[str]) -> bool:
        return is_saturated(value, match, self._config.full_scale, self._saturated_status)

    # -- stop -------------------------------------------------------------------------

    def stop_stream(self) -> list[StreamReading]:
        """Stop the stream (idempotent; nothing is sent when none runs) and return the
        readings that arrived until the device acknowledged ``stop`` (with a
        ``command_ack``: the device sends it after its last line) or, without one, went
        quiet: at least ``max(3 periods, 50 ms)`` without a line; waited at most ``3 ×
        timeout_s``. The device is then idle and ``measure`` works; a device still
        streaming after that raises (``timeout``) and the next call first waits for
        quiet."""
        stream = self._stream
        if stream is None or self._serial is None:
            self._stream = None
            return []
        cfg = self._stream_config()
        readings: list[StreamReading] = []
        with contextlib.suppress(SerialDetectorError):  # a bad last line does not matter
            readings += self._parse_pending(stream)
        try:
            stream.stop_sent_s = self._clock.now()
            self._send(cfg.stop)
            stream.stopping = True
            quiet = max(3 * stream.period_s, _QUIET_MIN_S)
            start = time.monotonic()
            give_up = start + 3 * self._config.timeout_s
            if self._ack is not None:
                readings += self._until_acknowledged(stream, give_up)
                return readings
            quiet_until = start + quiet
            while time.monotonic() < quiet_until:
                if time.monotonic() > give_up:
                    self._needs_resync = True
                    raise self._error(
                        f"the device kept streaming {3 * self._config.timeout_s:.3g} s "
                        f"after {cfg.stop!r}",
                        "timeout",
                    )
                data_lines = len(stream.pending)
                self._pump(stream, block=True)
                if len(stream.pending) > data_lines:
                    quiet_until = time.monotonic() + quiet
            with contextlib.suppress(SerialDetectorError):
                readings += self._parse_pending(stream)
        finally:
            self._stream = None
            self._keep_trace(stream)
            self._clear_input_state()
        return readings

    def _until_acknowledged(self, stream: _Stream, give_up: float) -> list[StreamReading]:
        """The readings that arrive until ``stop``'s acknowledgement (by ``give_up``,
        monotonic s, else ``timeout``, the next call waiting for quiet first)."""
        readings: list[StreamReading] = []
        while not stream.stopped:
            if time.monotonic() > give_up:
                self._needs_resync = True
                cfg = self._stream_config()
                raise self._error(
                    f"the device did not acknowledge {cfg.stop!r} within "
                    f"{3 * self._config.timeout_s:.3g} s",
                    "timeout",
                )
            self._pump(stream, block=True)
            with contextlib.suppress(SerialDetectorError):  # a bad last line does not matter
                readings += self._parse_pending(stream)
        return readings

    def listen(self, duration_s: float) -> list[tuple[str, float]]:
        """The lines that arrive unasked in the next ``duration_s`` seconds, each with the
        clock when it was read (s): what a device sends after its stream was stopped.
        ``streaming`` error while a stream runs (read it with `read_stream`)."""
        if self._serial is None:
            raise self._error("the port is not open (use open() first)", "closed")
        if self._stream is not None:
            raise self._error("listen() during a stream (read_stream reads it)", "streaming")
        heard: list[tuple[str, float]] = []
        deadline = time.monotonic() + max(0.0, float(duration_s))
        while time.monotonic() < deadline:
            self._receive()
            now = self._clock.now()
            heard += [(line.text, now) for line in self._lines]
            self._lines.clear()
        return heard

    def _quiet_stream(self) -> None:
        """After opening, with a stream section: send ``stop`` (a device still
        streaming for a killed run stops; an idle one answers or refuses it) and discard
        what arrives until 50 ms of quiet (at most ``3 × timeout_s``)."""
        cfg = self._config.stream
        if cfg is None:
            return
        self._send(cfg.stop)
        start = time.monotonic()
        quiet_until, give_up = start + _QUIET_MIN_S, start + 3 * self._config.timeout_s
        while time.monotonic() < min(quiet_until, give_up):
            if self._receive():
                quiet_until = time.monotonic() + _QUIET_MIN_S
        self._clear_input_state()

    def _abort_stream(self) -> None:
        """After a failure mid-stream: ask the device to stop, listen it out next time."""
        cfg = self._config.stream
        if self._stream is not None:
            self._keep_trace(self._stream)
        self._stream = None
        if self._serial is not None and cfg is not None:
            with contextlib.suppress(Exception):
                self._send(cfg.stop)
            self._needs_resync = True
