"""The driver: :class:`SerialDetector`, a :class:`drivers.base.Detector` on a line-based
serial protocol (see the package docstring and ``docs/reference/serial_detector.md``)."""

from __future__ import annotations

import contextlib
import logging
import math
import re
import statistics
import time

from drivers.base import Clock, SystemClock
from drivers.devices import Resource
from drivers.serial_detector.arguments import integrated, measure_arguments, template_values
from drivers.serial_detector.config import SerialDetectorConfig
from drivers.serial_detector.errors import SerialDetectorClosed, SerialDetectorError
from drivers.serial_detector.lines import Line, LineIO, is_saturated, number, pattern, quote
from drivers.serial_detector.stream import StreamContext, Streaming
from drivers.serial_detector.trace import StreamTrace
from drivers.stream import StreamReading
from drivers.values import Reading

log = logging.getLogger("drivers.serial_detector")  # one logger for the package

#: Failures after which nothing more is owed by the device: no resync needed.
_ANSWERED = frozenset({"reset", "device", "value", "invalid"})


class SerialDetector(Resource):
    """A :class:`drivers.base.Detector` on a line-based serial protocol.

    Use it as a context manager (``with SerialDetector(config) as det: det.measure(0.1)``)
    or call :meth:`open` and :meth:`close`. It holds its lines
    (:class:`~drivers.serial_detector.lines.LineIO`: the port, what was received, raw I/O
    and the error messages) and, with a ``stream`` section, streams
    (`drivers.stream.StreamingDetector`) through the
    :class:`~drivers.serial_detector.stream.Streaming` it holds.

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
        self._error_reply = pattern(config.error_reply)
        self._saturated_status = pattern(config.saturated_status)
        self._fields = config.template_fields
        self._io = LineIO(config, on_reset=self._note_reset, on_lost=self._lost)
        self._streaming = Streaming(
            StreamContext(
                config,
                self._io,
                self._clock,
                self._exposure_range,
                usable=self._check_usable,
                prepare=self._prepare,
                check_unsolicited=self._check_unsolicited,
                lost_sync=self._lost_sync,
            )
        )
        self._needs_init = False
        self._needs_resync = False
        self._reopen = False  # closed by the driver after an I/O error: reopen on next call
        self._exposure_command: str | None = None  # the last set_exposure sent
        self._resets = 0

    # -- properties ---------------------------------------------------------------

    @property
    def config(self) -> SerialDetectorConfig:
        return self._config

    @property
    def port(self) -> str:
        return self._config.port

    @property
    def is_open(self) -> bool:
        return self._io.is_open

    @property
    def exposure_range_s(self) -> tuple[float, float]:
        return self._exposure_range

    @property
    def resynced_away(self) -> int:
        """Lines a resync after a failed exchange discarded before its acknowledgement
        (late answers among them), since the detector was made."""
        return self._io.synced_away

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
        if self._io.is_open:
            return
        self._io.open()
        self._reopen = False
        try:
            self._io.settle()
            self._streaming.quiet()  # a stream left running (a killed run) is stopped
            self._initialize()
        except BaseException:
            self._release()
            raise

    def close(self) -> None:
        """Release the port (idempotent). Unsent bytes are dropped, not waited for; a
        running stream is stopped first (`stop_stream`)."""
        self._reopen = False
        if self._streaming.running:
            with contextlib.suppress(Exception):  # bounded: 3 × timeout_s at most
                self.stop_stream()
        self._release()

    def _release(self) -> None:
        self._needs_init = False
        self._needs_resync = False
        self._exposure_command = None
        self._streaming.drop()
        self._io.close()

    def _lost(self) -> None:
        """An OS error ended the port: released, and reopened on the next call."""
        self._release()
        self._reopen = True

    def _check_usable(self) -> None:
        """`SerialDetectorClosed` unless the port is open or was lost (to be reopened)."""
        if not self._io.is_open and not self._reopen:
            raise SerialDetectorClosed(
                f"serial detector {self.port}: the port is not open (use "
                "`with SerialDetector(config) as det:` or call open() first)",
                port=self.port,
                kind="closed",
            )

    def _lost_sync(self) -> None:
        """An exchange failed: a late answer may still come; listen it out first."""
        self._needs_resync = True

    # -- measuring ----------------------------------------------------------------

    def measure(self, exposure_s: float, averages: int = 1) -> Reading:
        """Expose for ``exposure_s`` seconds, ``averages`` times, and return the mean.

        ``std`` is the sample standard deviation (ddof 1; 0 for one sample). With
        ``device_averaging`` it is the device's ``std`` group, or NaN if the device
        does not report one, and ``raw`` holds the device's mean only.
        """
        self._check_usable()
        exposure_s, averages = measure_arguments(
            self._fields, self._exposure_range, self.port, exposure_s, averages
        )
        if self._streaming.running:
            raise self._io.error("measure() during a stream (stop_stream first)", "streaming")
        if not self._io.is_open:
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
            if not answered and self._io.is_open:
                # A late answer to the interrupted query may still come (after a timeout,
                # malformed lines, Ctrl-C): listen it out before the next query.
                self._lost_sync()
            raise
        log.debug("%s: %s", self.port, reading)
        return reading

    def ask(self, command: str) -> str:
        """Send ``command`` (no template fields) and return the first line answered
        within ``timeout_s``, an echo skipped: an identification query (``ID?``,
        ``*IDN?``) or any other one-line exchange. Fails as a query does (``timeout``,
        ``device`` for an error reply, ``reset``); ``streaming`` during a stream."""
        if not self._io.is_open and not self._reopen:
            raise self._io.error("the port is not open (use open() first)", "closed")
        if not isinstance(command, str) or not command.strip() or not command.isascii():
            raise self._io.invalid(f"a command must be a non-empty ASCII string, got {command!r}")
        if "\r" in command or "\n" in command:
            raise self._io.invalid(f"a command must not contain a line ending, got {command!r}")
        if self._streaming.running:
            raise self._io.error("ask() during a stream (stop_stream first)", "streaming")
        if not self._io.is_open:
            self.open()
        try:
            self._ready()
            self._io.send(command)
            deadline = time.monotonic() + self._config.timeout_s
            while (line := self._io.next_line(deadline)) is not None:
                self._check_unsolicited(line, command)
                if line.overflow or line.text != command.strip():
                    return line.text
            raise self._io.timeout(command, self._config.timeout_s, "answer")
        except BaseException as exc:
            answered = isinstance(exc, SerialDetectorError) and exc.kind in _ANSWERED
            if not answered and self._io.is_open:
                self._lost_sync()
            raise

    def _host_averaged(self, exposure_s: float, averages: int, started: float) -> Reading:
        command = self._config.query.format(**template_values(exposure_s, averages))
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
            exposure_s=integrated(self._fields, exposure_s),
        )

    def _device_averaged(self, exposure_s: float, averages: int, started: float) -> Reading:
        command = self._config.query.format(**template_values(exposure_s, averages))
        budget = exposure_s * averages + self._config.timeout_s
        value, match = self._query(command, budget)
        std = math.nan
        std_text = match.groupdict().get("std")
        if std_text is not None:
            parsed = number(std_text)
            if parsed is None or not math.isfinite(parsed) or parsed < 0:
                line = match.string
                raise self._io.error(
                    f"the device's standard deviation {std_text!r} in {quote(line)} "
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
            exposure_s=integrated(self._fields, exposure_s),
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
        malformed: list[Line] = []
        for attempt in range(cfg.retries + 1):
            if attempt:
                log.warning(
                    "%s: no valid answer to %r after %s; asking again",
                    self.port,
                    command,
                    malformed[-1].quoted(),
                )
                self._io.drain()
            self._io.send(command)
            deadline = time.monotonic() + budget_s
            heard = False
            while (line := self._io.next_line(deadline)) is not None:
                self._check_unsolicited(line, command)
                if not line.overflow:
                    if line.text == command.strip():  # the device echoes commands
                        continue
                    if self._stray_ack(line.text):  # a resync's, sent again
                        continue
                    match = self._response.fullmatch(line.text)
                    if match is not None:
                        value = number(match.group("value"))
                        if value is not None:
                            if not math.isfinite(value):
                                raise self._io.error(
                                    f"the device answered a non-finite value "
                                    f"{match.group('value')!r} in {quote(line.text)} "
                                    f"to {command!r}",
                                    "value",
                                    line.text,
                                )
                            return value, match
                heard = True
                malformed.append(line)
                log.warning("%s: malformed answer to %r: %s", self.port, command, line.quoted())
                if len(malformed) > cfg.retries:
                    raise self._io.malformed(command, malformed)
            if not malformed:
                raise self._io.timeout(command, budget_s, "answer")
        if not heard:
            raise self._io.timeout(
                command,
                budget_s,
                "answer",
                f"after {len(malformed)} malformed line(s), the last {malformed[-1].quoted()}",
            )
        raise self._io.malformed(command, malformed)

    def _stray_ack(self, text: str) -> bool:
        """An acknowledgement where an answer was awaited: a resync sent its command
        again and the earlier one's came late (never a value)."""
        ack = self._io.ack
        if ack is None or ack.search(text) is None:
            return False
        return self._response.fullmatch(text) is None

    def _command(self, command: str) -> None:
        """Send an init or set-exposure command and, with ``command_ack``, wait for it."""
        self._io.send(command)
        ack = self._io.ack
        if ack is None:
            return
        cfg = self._config
        deadline = time.monotonic() + cfg.timeout_s
        malformed: list[Line] = []
        while (line := self._io.next_line(deadline)) is not None:
            self._check_unsolicited(line, command)
            if not line.overflow:
                if line.text == command.strip():
                    continue
                if ack.search(line.text):
                    return
            malformed.append(line)
            log.warning("%s: unexpected answer to %r: %s", self.port, command, line.quoted())
            if len(malformed) > cfg.retries:
                raise self._io.malformed(command, malformed, expected="an acknowledgement")
        raise self._io.timeout(command, cfg.timeout_s, "acknowledgement")

    def _check_unsolicited(self, line: Line, command: str) -> None:
        """Raise on a reset banner or an error reply received while waiting."""
        if line.overflow:
            return
        banner = self._io.banner
        if banner is not None and banner.search(line.text):
            self._note_reset()
            raise self._io.error(
                f"device reset during a reading: it printed {quote(line.text)} while the "
                f"driver waited for the answer to {command!r}; it will be re-initialized on "
                f"the next call",
                "reset",
                line.text,
            )
        if self._error_reply is not None and self._error_reply.search(line.text):
            raise self._io.error(
                f"the device refused {command!r}: {quote(line.text)}", "device", line.text
            )

    def _ready(self) -> None:
        """Bring the instrument to a known state before a command: resynchronised after
        a lost exchange, unread input dropped, initialised again after a reset."""
        if self._needs_resync:
            self._io.resync(self._exposure_command or next(iter(self._config.init), None))
            self._needs_resync = False
        self._io.drain()
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
        command = template.format(**template_values(exposure_s, 1))
        if command == self._exposure_command:
            return
        self._exposure_command = None
        self._command(command)
        self._exposure_command = command

    def _note_reset(self) -> None:
        self._resets += 1
        self._needs_init = True
        self._exposure_command = None

    # -- streaming (`drivers.serial_detector.stream`) -----------------------------------

    @property
    def can_stream(self) -> bool:
        """Whether the configuration has a streaming mode (`drivers.stream.can_stream`)."""
        return self._config.stream is not None

    @property
    def is_streaming(self) -> bool:
        return self._streaming.running

    @property
    def last_stream(self) -> StreamTrace | None:
        """What the driver saw of the last stream stopped or failed (`StreamTrace`), None
        before the first."""
        return self._streaming.last

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
        self._streaming.start(rate_hz, integration_s)

    def read_stream(self, timeout_s: float = 0.0) -> list[StreamReading]:
        """The readings received since the last call, in order; with none yet, wait up
        to ``timeout_s`` (s) for the first. Raises `SerialDetectorError` naming the port
        when the stream stalls (no line for ``timeout_s`` of the configuration plus two
        periods), on malformed lines beyond ``retries`` in a row, a reset, an error
        reply or a non-finite value; the stream is then stopped (best effort)."""
        return self._streaming.read(timeout_s)

    def stop_stream(self) -> list[StreamReading]:
        """Stop the stream (idempotent; nothing is sent when none runs) and return the
        readings that arrived until the device acknowledged ``stop`` (with a
        ``command_ack``: the device sends it after its last line) or, without one, went
        quiet: at least ``max(3 periods, 50 ms)`` without a line; waited at most ``3 ×
        timeout_s``. The device is then idle and ``measure`` works; a device still
        streaming after that raises (``timeout``) and the next call first waits for
        quiet."""
        return self._streaming.stop()

    def listen(self, duration_s: float) -> list[tuple[str, float]]:
        """The lines that arrive unasked in the next ``duration_s`` seconds, each with the
        clock when it was read (s): what a device sends after its stream was stopped.
        ``streaming`` error while a stream runs (read it with `read_stream`)."""
        return self._streaming.listen(duration_s)

    # -- the state of the instrument ---------------------------------------------------

    def _prepare(self) -> None:
        """Reopened after an I/O error, then `_ready`."""
        if not self._io.is_open:
            self.open()
        self._ready()
