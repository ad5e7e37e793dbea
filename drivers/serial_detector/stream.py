"""The streaming mode of a :class:`~drivers.serial_detector.detector.SerialDetector`:
`Streaming`, which the detector holds and which sees it through a `StreamContext`, does
its ``start_stream`` / ``read_stream`` / ``stop_stream`` (`drivers.stream.StreamingDetector`)
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
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

from drivers.base import Clock
from drivers.errors import StreamNotSupported
from drivers.serial_detector.arguments import stream_arguments
from drivers.serial_detector.config import SerialDetectorConfig, SerialStreamConfig
from drivers.serial_detector.errors import SerialDetectorError
from drivers.serial_detector.lines import Line, LineIO, is_saturated, number, pattern, quote
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
    malformed: list[Line] = field(default_factory=list)
    pending: deque[tuple[Line, float]] = field(default_factory=deque)
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


@dataclass(frozen=True)
class StreamContext:
    """What the stream uses of the detector that holds it: its configuration, lines and
    clock, the exposure range it allows (s), and its machinery as callables."""

    config: SerialDetectorConfig
    lines: LineIO
    clock: Clock
    exposure_range_s: tuple[float, float]
    usable: Callable[[], None]  # `SerialDetectorClosed` unless open, or lost and reopenable
    prepare: Callable[[], None]  # reopened if lost; resynchronized, drained, initialized
    check_unsolicited: Callable[[Line, str], None]  # raise on a reset or an error reply
    lost_sync: Callable[[], None]  # a late answer may come: listen it out before the next


class Streaming:
    """The streaming mode of the detector of ``context`` (see the module docstring):
    the running stream, if any, and what was seen of the last one."""

    def __init__(self, context: StreamContext) -> None:
        self._c = context
        config = context.config
        self._config = config
        self._line = None if config.stream is None else re.compile(config.stream.line)
        self._saturated_status = pattern(config.saturated_status)
        self._stream: _Stream | None = None
        self._last_trace: StreamTrace | None = None

    @property
    def running(self) -> bool:
        return self._stream is not None

    @property
    def last(self) -> StreamTrace | None:
        """What was seen of the last stream stopped or failed, None before the first."""
        return self._last_trace

    def drop(self) -> None:
        """Forget the running stream, untraced: the port was released under it."""
        self._stream = None

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
                f"serial detector {self._c.lines.port}: cannot stream: its configuration has no "
                "stream section (start, stop, line; docs/reference/serial_detector.md)"
            )
        return self._config.stream

    # -- start ------------------------------------------------------------------------

    def start(self, rate_hz: float | None, integration_s: float | None) -> None:
        """`SerialDetector.start_stream`."""
        cfg = self._stream_config()
        c = self._c
        c.usable()
        if self._stream is not None:
            raise c.lines.error("a stream is already running (stop_stream first)", "streaming")
        rate, integration, command = stream_arguments(
            cfg, c.exposure_range_s, c.lines.port, rate_hz, integration_s
        )
        try:
            c.prepare()
            sent = c.clock.now()
            c.lines.send(command)
        except BaseException:
            if c.lines.is_open:
                c.lost_sync()
            raise
        stall = self._config.timeout_s + 2.0 / rate
        stream = _Stream(rate, integration, command, time.monotonic(), stall, sent_s=sent)
        self._stream = stream
        if cfg.starts_on_command and c.lines.ack is not None:
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
            self._abort()
            raise

    # -- read -------------------------------------------------------------------------

    def read(self, timeout_s: float) -> list[StreamReading]:
        """`SerialDetector.read_stream`."""
        stream = self._stream
        if stream is None:
            raise self._c.lines.error("no stream is running (start_stream first)", "streaming")
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
            self._abort()
            raise

    def _pump(self, stream: _Stream, *, block: bool) -> None:
        """Receive what has arrived (``block``: waiting at most the poll interval) and
        stamp the new lines with the host clock."""
        lines = self._c.lines
        if block or lines.in_waiting():
            lines.receive()
        received = self._c.clock.now()
        new = lines.take_lines()
        if new:
            stream.last_line = time.monotonic()
        stream.pending.extend((line, received) for line in new)

    def _check_stall(self, stream: _Stream) -> None:
        quiet = time.monotonic() - stream.last_line
        if quiet > stream.stall_s:
            raise self._c.lines.error(
                f"the stream stopped: no line for {quiet:.3g} s (at {stream.rate_hz:g} Hz, "
                f"after {stream.start!r}; is the device on, speaking this protocol?)",
                "timeout",
            )

    def _parse_pending(self, stream: _Stream) -> list[StreamReading]:
        """Readings from the stamped lines received (data lines only)."""
        cfg = self._stream_config()
        assert self._line is not None
        ack = self._c.lines.ack
        parsed: list[tuple[float, float, bool, float | None, float, float]] = []
        while stream.pending:
            line, received = stream.pending.popleft()
            self._c.check_unsolicited(line, stream.start)
            match = None if line.overflow else self._line.fullmatch(line.text)
            if match is None:
                if not line.overflow and ack is not None and ack.search(line.text):
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
                    raise self._c.lines.error(
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
            earliest = None
            if cfg.starts_on_command:  # between the start command's bounds
                earliest = clock + stream.start_offset_s
                end = min(end, clock + stream.ack_offset_s - cfg.latency_s)
                end = max(end, earliest)
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
                    earliest_end_s=earliest,
                )
            )
        return readings

    def _finite(self, match: re.Match[str], group: str, line: Line) -> float:
        parsed = number(match.group(group))
        if parsed is None or not math.isfinite(parsed) or (group == "std" and parsed < 0):
            raise self._c.lines.error(
                f"the stream's {group} {match.group(group)!r} in {quote(line.text)} is not "
                "a finite number" + (" ≥ 0" if group == "std" else ""),
                "value",
                line.text,
            )
        return parsed

    def _saturated(self, value: float, match: re.Match[str]) -> bool:
        return is_saturated(value, match, self._config.full_scale, self._saturated_status)

    # -- stop -------------------------------------------------------------------------

    def stop(self) -> list[StreamReading]:
        """`SerialDetector.stop_stream`."""
        c = self._c
        stream = self._stream
        if stream is None or not c.lines.is_open:
            self._stream = None
            return []
        cfg = self._stream_config()
        readings: list[StreamReading] = []
        with contextlib.suppress(SerialDetectorError):  # a bad last line does not matter
            readings += self._parse_pending(stream)
        try:
            stream.stop_sent_s = c.clock.now()
            c.lines.send(cfg.stop)
            stream.stopping = True
            quiet = max(3 * stream.period_s, _QUIET_MIN_S)
            start = time.monotonic()
            give_up = start + 3 * self._config.timeout_s
            if c.lines.ack is not None:
                readings += self._until_acknowledged(stream, give_up)
                return readings
            quiet_until = start + quiet
            while time.monotonic() < quiet_until:
                if time.monotonic() > give_up:
                    self._c.lost_sync()
                    raise self._c.lines.error(
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
            c.lines.clear()
        return readings

    def _until_acknowledged(self, stream: _Stream, give_up: float) -> list[StreamReading]:
        """The readings that arrive until ``stop``'s acknowledgement (by ``give_up``,
        monotonic s, else ``timeout``, the next call waiting for quiet first)."""
        readings: list[StreamReading] = []
        while not stream.stopped:
            if time.monotonic() > give_up:
                self._c.lost_sync()
                cfg = self._stream_config()
                raise self._c.lines.error(
                    f"the device did not acknowledge {cfg.stop!r} within "
                    f"{3 * self._config.timeout_s:.3g} s",
                    "timeout",
                )
            self._pump(stream, block=True)
            with contextlib.suppress(SerialDetectorError):  # a bad last line does not matter
                readings += self._parse_pending(stream)
        return readings

    def listen(self, duration_s: float) -> list[tuple[str, float]]:
        """`SerialDetector.listen`."""
        lines = self._c.lines
        if not lines.is_open:
            raise lines.error("the port is not open (use open() first)", "closed")
        if self._stream is not None:
            raise lines.error("listen() during a stream (read_stream reads it)", "streaming")
        heard: list[tuple[str, float]] = []
        deadline = time.monotonic() + max(0.0, float(duration_s))
        while time.monotonic() < deadline:
            lines.receive()
            now = self._c.clock.now()
            heard += [(line.text, now) for line in lines.take_lines()]
        return heard

    def quiet(self) -> None:
        """After opening, with a stream section: send ``stop`` (a device still
        streaming for a killed run stops; an idle one answers or refuses it) and discard
        what arrives until 50 ms of quiet (at most ``3 × timeout_s``)."""
        cfg = self._config.stream
        if cfg is None:
            return
        lines = self._c.lines
        lines.send(cfg.stop)
        start = time.monotonic()
        quiet_until, give_up = start + _QUIET_MIN_S, start + 3 * self._config.timeout_s
        while time.monotonic() < min(quiet_until, give_up):
            if lines.receive():
                quiet_until = time.monotonic() + _QUIET_MIN_S
        lines.clear()

    def _abort(self) -> None:
        """After a failure mid-stream: ask the device to stop, listen it out next time."""
        cfg = self._config.stream
        if self._stream is not None:
            self._keep_trace(self._stream)
        self._stream = None
        if self._c.lines.is_open and cfg is not None:
            with contextlib.suppress(Exception):
                self._c.lines.send(cfg.stop)
            self._c.lost_sync()
