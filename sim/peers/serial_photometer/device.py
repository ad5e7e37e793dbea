"""The simulated photometer itself: its settings and how it answers each command and
streams (see the package docstring for the protocol). It holds its `Sensor` (what an
exposure reads, `sim.peers.serial_photometer.sensor`) and the `Faults` a test injects
(`sim.peers.serial_photometer.faults`)."""

from __future__ import annotations

import math
import random
import termios
import time
from collections.abc import Callable
from typing import Any

from drivers.serial_detector import SerialDetectorConfig
from sim.peers.line_server import Event, LineServer, ServedPeer
from sim.peers.serial_photometer.faults import Faults
from sim.peers.serial_photometer.protocol import BANNER, IDENTITY, _int_in, _line, default_config
from sim.peers.serial_photometer.quirks import CONFORMING, StreamQuirks
from sim.peers.serial_photometer.sensor import Sensor, Signal

#: Stream windows' counts in one call: given the windows' starts and ends
#: (`time.monotonic` s), their counts and saturated flags (one each).
Windows = Callable[[list[float], list[float]], tuple[list[float], list[bool]]]
#: With ``windows``: the shortest real time (s) between two bursts of stream lines (a
#: USB serial adapter's latency timer sends in bursts as well).
BURST_S = 0.004
#: The highest rate (Hz) the simulated photometer streams at.
MAX_STREAM_RATE_HZ = 2000.0


class SerialPhotometer(ServedPeer):
    """A photometer on a pseudo-terminal.

    ``signal`` is a constant rate in counts per second (the reading is rate × exposure)
    or a callable taking the exposure in seconds and returning the counts of one
    exposure. Gaussian noise of ``noise_std`` counts (from ``random.Random(seed)``) and
    ``dark`` counts are added, the sum is multiplied by the gain, and readings at or
    above ``full_scale`` are clipped to it with the status ``SAT`` (``None``: no
    clipping). ``reply_delay_s`` is added to every answer. With ``reset_on_open`` the
    device reboots when a host opens the port (as an Arduino does when DTR rises) and
    prints its banner ``boot_s`` later. ``echo`` echoes every command line. With
    ``speedup`` an exposure of t s takes t / ``speedup`` real seconds (a rehearsal's
    scaled time; the counts are still those of t s).

    A stream's windows are read at their middle through ``signal``, one exposure each,
    as the pose is then; with ``windows`` instead, all the windows ended when the serving
    thread wakes are read in one call from their true start and end times (what a
    rehearsal needs when one exposure costs more than a sped-up period: the lines then
    come in bursts, each stamped with its window's end).

    The pty and the serving thread are its `sim.peers.line_server.LineServer`'s.
    """

    def __init__(
        self,
        signal: Signal = 20_000.0,
        *,
        noise_std: float = 0.0,
        dark: float = 0.0,
        full_scale: float | None = 65535.0,
        reply_delay_s: float = 0.0,
        default_exposure_ms: int = 10,
        reset_on_open: bool = False,
        boot_s: float = 0.0,
        echo: bool = False,
        seed: int = 0,
        speedup: float = 1.0,
        windows: Windows | None = None,
        quirks: StreamQuirks = CONFORMING,
    ) -> None:
        if not callable(signal) and not math.isfinite(signal):
            raise ValueError(f"signal must be finite or a callable, got {signal!r}")
        if noise_std < 0 or reply_delay_s < 0 or boot_s < 0:
            raise ValueError("noise_std, reply_delay_s and boot_s must be ≥ 0")
        if not (math.isfinite(speedup) and speedup > 0):
            raise ValueError(f"speedup must be finite and > 0, got {speedup!r}")
        if windows is not None and quirks != CONFORMING:
            raise ValueError("quirks apply to a stream read window by window, not with windows")
        if full_scale is not None and not full_scale > 0:
            raise ValueError(f"full_scale must be > 0 or None, got {full_scale!r}")
        if reset_on_open and not hasattr(termios, "TIOCPKT"):  # pragma: no cover
            raise ValueError("reset_on_open needs TIOCPKT, not available on this system")
        self._sensor = Sensor(signal, noise_std, dark, full_scale, seed)
        self._reply_delay_s = reply_delay_s
        self._default_exposure_ms = default_exposure_ms
        self._boot_s = boot_s
        self._echo = echo
        self._speedup = float(speedup)
        self._windows_signal = windows
        self._stream_from = 0.0  # time.monotonic() the running stream's first window began
        self._stream_sent = 0  # windows of the running stream read so far
        self._quirks = quirks
        self._quirk_rng = random.Random(seed + 1)
        self._stream_index = 0  # data lines of the running stream so far
        self._stop_after: int | None = None  # lines still sent after an acknowledged STOP
        self._stop_ack_due = 0.0  # time.monotonic() that acknowledgement is sent

        super().__init__(
            LineServer(
                "photometer",
                self._handle,
                self._reset_locked,
                self._tick_locked,
                reset_on_open=reset_on_open,
            )
        )
        self._lock = self._server.lock
        self._faults = Faults()
        self._exposure_ms = default_exposure_ms
        self._gain = 1
        self._busy_until = 0.0
        self._commands: list[str] = []
        self._resets = 0
        self._stream: tuple[float, float] | None = None  # (period real s, integration s)
        self._stream_gen = 0  # a tick of an older generation is a stopped stream's
        self._window: tuple[float, bool] | Exception | None = None  # read at its middle
        self._stream_ends: list[float] = []  # time.monotonic() of each DAT line's window end
        self._t0 = time.monotonic()  # the device's clock starts at zero here
        self._server.link_latency_s = quirks.link_latency_s

    # -- configuration -------------------------------------------------------------

    def config(self, **overrides: Any) -> SerialDetectorConfig:
        """:func:`default_config` for this device's path."""
        return default_config(self.path, **overrides)

    # -- inspection ---------------------------------------------------------------

    @property
    def commands(self) -> list[str]:
        """Every command line received so far, in order."""
        with self._lock:
            return list(self._commands)

    @property
    def exposure_ms(self) -> int:
        with self._lock:
            return self._exposure_ms

    @property
    def gain(self) -> int:
        with self._lock:
            return self._gain

    @property
    def resets(self) -> int:
        """How many times the device has rebooted."""
        with self._lock:
            return self._resets

    @property
    def streaming(self) -> bool:
        """Whether the device is streaming."""
        with self._lock:
            return self._stream is not None

    @property
    def stream_ends(self) -> list[float]:
        """The `time.monotonic` time each streamed line's window ended (the truth a
        latency measurement compares the host's stamps with), in order."""
        with self._lock:
            return list(self._stream_ends)

    def device_time_s(self, monotonic_s: float) -> float:
        """The device's clock (s, scaled by ``speedup``) at a `time.monotonic` time."""
        return (monotonic_s - self._t0) * self._speedup

    def clear_commands(self) -> None:
        with self._lock:
            self._commands.clear()

    # -- fault injection ------------------------------------------------------------

    def malformed(self, count: int = 1) -> None:
        """Answer the next ``count`` measurements with :data:`MALFORMED_LINE`."""
        with self._lock:
            self._faults.malformed += count

    def inject(self, *lines: str) -> None:
        """Answer the next measurements with these lines, verbatim (e.g. ``"VAL nan OK"``)."""
        with self._lock:
            self._faults.inject.extend(lines)

    def silent(self) -> None:
        """Ignore every command until :meth:`clear`; a stream stops at its next window."""
        with self._lock:
            self._faults.silent = True

    def reset_mid_read(self) -> None:
        """Reboot half-way through the next measurement instead of answering it."""
        with self._lock:
            self._faults.reset_next = True

    def slow(self, seconds: float) -> None:
        """Delay every answer by ``seconds`` more, until :meth:`clear`."""
        with self._lock:
            self._faults.slow_s = seconds

    def late(self, seconds: float, count: int = 1) -> None:
        """Send the next ``count`` answers ``seconds`` late; the device is busy meanwhile,
        so what it answers after them waits behind them (lines keep their order)."""
        if not seconds > 0 or count < 1:
            raise ValueError(f"a late answer needs seconds > 0 and count ≥ 1, got {seconds!r}")
        with self._lock:
            self._faults.late.extend([seconds] * count)

    def garbage_without_newline(self, nbytes: int) -> None:
        """Answer the next measurement with ``nbytes`` digits and no line ending."""
        with self._lock:
            self._faults.garbage = nbytes

    def unsolicited(self, line: str) -> None:
        """Send ``line`` now, unasked (a debug print, a stray message)."""
        self._server.schedule(time.monotonic(), _line(line))

    def reboot(self) -> None:
        """Reset now: forget the settings and print the banner after ``boot_s``."""
        with self._lock:
            self._reset_locked(time.monotonic())
        self._server.wakeup()

    def set_quirks(self, quirks: StreamQuirks) -> None:
        """Stream with ``quirks`` from the next ``STREAM`` on (`StreamQuirks`)."""
        if self._windows_signal is not None and quirks != CONFORMING:
            raise ValueError("quirks apply to a stream read window by window, not with windows")
        with self._lock:
            self._quirks, self._server.link_latency_s = quirks, quirks.link_latency_s

    def clear(self) -> None:
        """Remove every fault."""
        with self._lock:
            self._faults = Faults()

    # -- the protocol ---------------------------------------------------------------

    def _reset_locked(self, now: float, *, banner_now: bool = False) -> None:
        """Reboot: pending answers are lost, settings return to their defaults."""
        self._server.events.clear()
        self._stream, self._stream_gen = None, self._stream_gen + 1
        self._exposure_ms = self._default_exposure_ms
        self._gain = 1
        self._busy_until = now + (0.0 if banner_now else self._boot_s)
        self._resets += 1
        self._server.schedule_locked(self._busy_until, _line(BANNER))

    def _handle(self, line: str, now: float) -> None:
        with self._lock:
            self._commands.append(line)
            if self._echo:
                self._server.output_locked(_line(line))
            faults = self._faults
            if faults.silent:
                return
            start = max(now, self._busy_until)
            delay = self._reply_delay_s + faults.slow_s
            delay += faults.late.popleft() if faults.late else 0.0
            words = line.split()
            name, args = words[0].upper(), words[1:]
            if name == "STOP" and not args:  # idle already: acknowledged all the same
                if self._stream is not None and self._windows_signal is not None:
                    self._send_windows_locked(now)  # the windows ended before it
                quirks, streaming = self._quirks, self._stream is not None
                ack_s = quirks.stop_ack_delay_s if streaming else 0.0
                delay += ack_s or 0.0
                if streaming and quirks.lines_after_stop_ack:
                    # lines of windows ending after the OK is sent: a window overdue on a
                    # busy host goes out before the OK and is not one of them
                    self._stop_after = quirks.lines_after_stop_ack
                    self._stop_ack_due = start + delay
                else:
                    self._stream, self._stream_gen = None, self._stream_gen + 1
                if ack_s is None:
                    return
                answer = "OK"
            elif name == "STREAM":
                answer = self._start_stream_locked(args, start + delay)
            elif self._stream is not None:
                answer = f"ERR streaming: {line}"
            elif name == "MEAS":
                self._measure_locked(args, start, delay)
                return
            elif name == "EXP" and len(args) == 1 and _int_in(args[0], 1, 60_000):
                self._exposure_ms = int(args[0])
                answer = "OK"
            elif name == "GAIN" and len(args) == 1 and _int_in(args[0], 1, 64):
                self._gain = int(args[0])
                answer = "OK"
            elif name in ("EXP", "GAIN"):
                answer = f"ERR bad argument: {line}"
            elif name == "ID?" and not args:
                answer = IDENTITY
            else:
                answer = f"ERR unknown command: {line}"
            self._busy_until = start + delay
            self._server.schedule_locked(self._busy_until, _line(answer))

    def _start_stream_locked(self, args: list[str], at: float) -> str:
        """``STREAM <rate_hz> <integration_ms>``: windows end every period from ``at``."""
        try:
            rate, integration_ms = float(args[0]), int(args[1])
        except (ValueError, IndexError):
            return f"ERR bad arguments: STREAM {' '.join(args)}"
        if len(args) != 2 or not 0 < rate <= MAX_STREAM_RATE_HZ or integration_ms < 1:
            return f"ERR bad arguments: STREAM {' '.join(args)}"
        if integration_ms / 1000 > 1 / rate + 1e-9:
            return f"ERR integration {integration_ms} ms longer than the period"
        period, integration = 1 / rate / self._speedup, integration_ms / 1000
        self._stream, self._stream_gen = (period, integration), self._stream_gen + 1
        self._window = None
        self._stream_index, self._stop_after = 0, None
        if self._windows_signal is not None:  # the windows ended, read in one call
            self._stream_from, self._stream_sent = at, 0
            self._server.tick_locked(at + period, self._stream_gen)
            return "OK"
        middle = self._quirks.first_end(at, period, self._t0) - integration / self._speedup / 2
        self._server.tick_locked(middle, self._stream_gen, middle=True)
        return "OK"

    def _burst_locked(self, event: Event) -> None:
        """With ``windows``: send a line for every window ended by now, then wake at the
        next window's end."""
        if self._faults.silent:  # the stream stops, as a crashed sketch's would
            self._stream = None
            return
        self._send_windows_locked(max(time.monotonic(), event.due))
        assert self._stream is not None
        following = self._stream_from + (self._stream_sent + 1) * self._stream[0]
        following = max(following, time.monotonic() + BURST_S)
        self._server.tick_locked(following, event.tick)

    def _send_windows_locked(self, now: float) -> None:
        """A line for each window of the running stream ended by ``now`` and not yet
        sent, their counts read in one call (with ``windows``)."""
        assert self._stream is not None and self._windows_signal is not None
        period, integration = self._stream
        done = math.floor((now - self._stream_from) / period + 1e-9)
        ends = [self._stream_from + (k + 1) * period for k in range(self._stream_sent, done)]
        self._stream_sent = max(done, self._stream_sent)
        if not ends:
            return
        starts = [end - integration / self._speedup for end in ends]
        try:
            counts, saturated = self._windows_signal(starts, ends)
            window: list[tuple[float, bool]] | Exception = [
                self._sensor.scaled(c, s, self._gain)
                for c, s in zip(counts, saturated, strict=True)
            ]
        except Exception as exc:  # a test's signal ran out of values, say
            window = exc
        for k, end in enumerate(ends):
            faulty = self._faults.line()
            if faulty is not None:
                data = faulty
            elif isinstance(window, list):
                value, sat = window[k]
                t_ms = self.device_time_s(end) * 1000
                self._stream_ends.append(end)
                data = _line(f"DAT {t_ms:.3f} {value!r} {'SAT' if sat else 'OK'}")
            else:
                data = _line(f"ERR signal failed: {type(window).__name__}")
            self._server.output_locked(data)

    def _tick_locked(self, event: Event) -> None:
        """A stream window's middle (``event.middle``: read the signal, as the pose is
        then) or end (send its line; schedule the next window's middle)."""
        if self._stream is None or event.tick != self._stream_gen:
            return
        if self._windows_signal is not None:
            self._burst_locked(event)
            return
        period, integration = self._stream
        half = integration / self._speedup / 2
        if event.middle:
            try:
                self._window = self._sensor.counts(integration, self._gain)
            except Exception as exc:  # a test's signal ran out of values, say
                self._window = exc
            self._server.tick_locked(event.due + half, event.tick)
            return
        faults = self._faults
        if faults.silent:  # the stream stops, as a crashed sketch's would
            self._stream = None
            return
        window, self._window = self._window, None
        faulty = self._faults.line()
        if faulty is not None:
            data = faulty
        elif isinstance(window, tuple):
            counts, saturated = window
            t_ms = self.device_time_s(event.due) * 1000
            status = "SAT" if saturated else "OK"
            index, self._stream_index = self._stream_index, self._stream_index + 1
            text = self._quirks.data_line(index, t_ms, period * self._speedup * 1e3, counts, status)
            if text is not None:
                self._stream_ends.append(event.due)
            data = b"" if text is None else _line(text)
        else:
            data = _line(f"ERR signal failed: {type(window).__name__}")
        self._server.output_locked(data)
        if self._stop_after is not None and event.due > self._stop_ack_due:
            self._stop_after -= 1  # a line after the acknowledged STOP
            if self._stop_after <= 0:
                self._stream, self._stream_gen, self._stop_after = None, self._stream_gen + 1, None
                return
        middle = event.due + self._quirks.next_period(period, self._quirk_rng) - half
        self._server.tick_locked(middle, event.tick, middle=True)

    def _measure_locked(self, args: list[str], start: float, delay: float) -> None:
        if len(args) > 2 or not all(_int_in(a, 1, 60_000) for a in args[:1]):
            self._server.schedule_locked(
                start + delay, _line(f"ERR bad argument: MEAS {' '.join(args)}")
            )
            return
        if len(args) == 2 and not _int_in(args[1], 1, 10_000):
            self._server.schedule_locked(start + delay, _line(f"ERR bad averages: {args[1]}"))
            return
        exposure_ms = int(args[0]) if args else self._exposure_ms
        count = int(args[1]) if len(args) == 2 else 1
        duration = exposure_ms / 1000 * count / self._speedup
        faults = self._faults
        if faults.reset_next:
            faults.reset_next = False
            self._busy_until = start + duration / 2
            self._server.schedule_locked(self._busy_until, reset=True)
            return
        done = start + duration + delay
        self._busy_until = done
        faulty = self._faults.line()
        answer = self._sensor.answer(exposure_ms / 1000, count, self._gain)
        data = faulty if faulty is not None else _line(answer)
        self._server.schedule_locked(done, data)
