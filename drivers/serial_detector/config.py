"""The configuration of a serial detector: :class:`SerialDetectorConfig`, its validation,
and the helpers that check command templates and regular expressions."""

from __future__ import annotations

import math
import numbers
import re
import string
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from drivers.described import described
from drivers.serial_detector.errors import SerialDetectorValueError

#: The fields a command template may use. Exposures are rounded to the nearest unit.
EXPOSURE_FIELDS = frozenset({"exposure_s", "exposure_ms", "exposure_us"})
QUERY_FIELDS = EXPOSURE_FIELDS | {"averages"}
#: The fields a stream's ``start`` template may use (rates in Hz, times rounded).
STREAM_FIELDS = frozenset(
    {"rate_hz", "period_ms", "period_us", "integration_s", "integration_ms", "integration_us"}
)
#: A streaming detector's rates (Hz): a reading every 100 s to 10⁵ a second, beyond what
#: a serial line carries (12 Mbaud of 16-byte lines is 75 000 lines a second).
STREAM_RATE_RANGE_HZ = (0.01, 1e5)
#: The largest count a detector's full scale may name: 10¹⁸, within float64's exact
#: integers' reach of a 64-bit counter.
MAX_FULL_SCALE = 1e18
_LINE_ENDINGS = ("\n", "\r\n", "\r")
_SAMPLE_FIELDS: Mapping[str, float | int] = {
    "exposure_s": 0.125,
    "exposure_ms": 125,
    "exposure_us": 125_000,
    "averages": 4,
}
_STREAM_SAMPLE: Mapping[str, float | int] = {
    "rate_hz": 100.0,
    "period_ms": 10,
    "period_us": 10_000,
    "integration_s": 0.008,
    "integration_ms": 8,
    "integration_us": 8_000,
}


@dataclass(frozen=True)
class SerialStreamConfig:
    """A detector's streaming mode (see ``docs/reference/serial_detector.md``,
    "Streaming"): ``start`` (a template of `STREAM_FIELDS`) makes it send one ``line``
    per integration window until ``stop``.

    ``line`` must match a whole data line: named groups ``value`` (required), optional
    ``device_t`` (the device's timestamp of the window's end, in units of
    ``device_time_s`` seconds), ``std``, ``status`` (saturated when it matches the
    detector's ``saturated_status``) and ``saturated``. ``latency_s`` is the delay from
    a window's end to its line's arrival that the host subtracts when the device sends
    no timestamp. ``max_rate_hz`` is the highest rate the instrument streams at;
    ``rate_hz`` the rate used when none is asked. ``starts_on_command``: the device
    begins its first window when the start command arrives (and acknowledges it then,
    with a ``command_ack``), so the host stamps the windows between the time it sent
    it and the time the acknowledgement came back (bounds the command's round trip
    keeps tight) rather than from the lines' arrival alone (which a late reader
    loosens).
    """

    start: str = field(
        default="STREAM {rate_hz:g} {integration_ms:d}",
        metadata=described(
            "The command that starts the stream: a template of {rate_hz}, {period_ms}, "
            "{period_us}, {integration_s}, {integration_ms} and {integration_us}."
        ),
    )
    stop: str = field(default="STOP", metadata=described("The command that stops it."))
    line: str = field(
        default=r"DAT (?P<device_t>\S+) (?P<value>\S+)",
        metadata=described(
            "A Python regex a whole data line matches: group value (required), optional "
            "device_t (the device's time of the window's end), std, status, saturated."
        ),
    )
    rate_hz: float = field(
        default=100.0,
        metadata=described(
            "The rate used when none is asked (Hz).",
            ge=STREAM_RATE_RANGE_HZ[0],
            le=STREAM_RATE_RANGE_HZ[1],
        ),
    )
    max_rate_hz: float = field(
        default=1000.0,
        metadata=described(
            "The highest rate it streams at (Hz).",
            ge=STREAM_RATE_RANGE_HZ[0],
            le=STREAM_RATE_RANGE_HZ[1],
        ),
    )
    device_time_s: float = field(
        default=1e-3,
        metadata=described("Seconds per unit of the device_t group (1e-3: milliseconds).", gt=0),
    )
    latency_s: float = field(
        default=0.0,
        metadata=described(
            "The shortest delay from a window's end to its line's arrival (s), subtracted "
            "from the host's stamps.",
            ge=0,
        ),
    )
    starts_on_command: bool = field(
        default=False,
        metadata=described(
            "The device begins its first window when the start command arrives (and, with a "
            "command_ack, acknowledges it then): the host stamps the windows between when it "
            "sent the command and when the acknowledgement came back."
        ),
    )

    def check(self, bad: Callable[[str], Exception]) -> None:
        """Raise ``bad(message)`` (a message starting ``stream.<field>``) for a bad field."""
        _template_fields(self.start, STREAM_FIELDS, "stream.start", bad, _STREAM_SAMPLE)
        _template_fields(self.stop, frozenset(), "stream.stop", bad)
        line = _compile(self.line, "stream.line", bad)
        if line is None or "value" not in line.groupindex:
            raise bad(f"stream.line {self.line!r} needs a named group (?P<value>...)")
        rate, top = as_real(self.rate_hz), as_real(self.max_rate_hz)
        if top is None or not 0 < top < math.inf:
            raise bad(f"stream.max_rate_hz must be a positive number, got {self.max_rate_hz!r}")
        if rate is None or not 0 < rate <= top:
            raise bad(
                f"stream.rate_hz must be a number in (0, max_rate_hz={top:g}], got {self.rate_hz!r}"
            )
        unit, latency = as_real(self.device_time_s), as_real(self.latency_s)
        if unit is None or not 0 < unit < math.inf:
            raise bad(
                f"stream.device_time_s must be a positive number of seconds, "
                f"got {self.device_time_s!r}"
            )
        if latency is None or not 0 <= latency < math.inf:
            raise bad(f"stream.latency_s must be ≥ 0 seconds, got {self.latency_s!r}")


@dataclass(frozen=True)
class SerialDetectorConfig:
    """How to talk to one line-based detector (see ``docs/reference/serial_detector.md``).

    Command templates (``query``, ``set_exposure``, ``init``) are ``str.format``
    templates; the fields are ``exposure_s`` (float, seconds), ``exposure_ms`` and
    ``exposure_us`` (ints, rounded), and in ``query`` also ``averages`` (int). Regular
    expressions: ``response`` must match the whole answer line (stripped); the others
    (``reset_banner``, ``command_ack``, ``error_reply``, ``saturated_status``) match
    anywhere in a line unless anchored.
    """

    port: str = field(metadata=described("The serial port, e.g. /dev/ttyACM0.", min_length=1))
    baud: int = field(default=115200, metadata=described("The baud rate.", gt=0))
    #: Sent once per sample, or once per measurement when ``device_averaging``.
    query: str = field(
        default="MEAS {exposure_ms:d}",
        metadata=described(
            "The command that asks for a reading: a template of {exposure_s}, {exposure_ms}, "
            "{exposure_us} and {averages}."
        ),
    )
    #: Sent before a query when the formatted command differs from the last one sent.
    set_exposure: str | None = field(
        default=None,
        metadata=described(
            "A command that sets the exposure, sent when its text changes (a template of "
            "{exposure_s}, {exposure_ms}, {exposure_us}; none: the query carries it)."
        ),
    )
    #: Named groups: ``value`` (required); optional ``status`` (saturated when it
    #: matches ``saturated_status``), ``saturated`` (saturated when it took part in the
    #: match and is not empty, 0, false, no, off) and ``std`` (the device's standard
    #: deviation, with ``device_averaging``).
    response: str = field(
        default=r"(?P<value>\S+)",
        metadata=described(
            "A Python regex the whole answer line matches: group value (required), optional "
            "status, saturated and std."
        ),
    )
    line_ending: str = field(
        default="\n",
        metadata=described(
            'What ends a command: lf, crlf or cr (or the characters in double quotes: "\\r\\n").'
        ),
    )
    timeout_s: float = field(
        default=1.0,
        metadata=described(
            "The margin on every deadline (s): a query waits its exposure (times the averages "
            "when the device averages) plus this, a command's acknowledgement this.",
            gt=0,
        ),
    )
    #: The query is sent again, at most this many more times, when a deadline passes
    #: after a malformed line.
    retries: int = field(
        default=2,
        metadata=described(
            "Malformed answers tolerated per reading (the query is sent again).", ge=0
        ),
    )
    full_scale: float | None = field(
        default=None,
        metadata=described(
            "Counts at or above which a reading is saturated (none: no such limit).",
            gt=0,
            le=MAX_FULL_SCALE,
        ),
    )
    reset_banner: str | None = field(
        default=None,
        metadata=described(
            "A Python regex of the line the device prints after a reset, e.g. ^READY."
        ),
    )
    init: tuple[str, ...] = field(
        default=(),
        metadata=described("Commands sent after opening and after a reset (no template fields)."),
    )
    #: An Arduino reboots when the port opens.
    settle_s: float = field(
        default=0.0,
        metadata=described(
            "After opening, wait up to this long for reset_banner, or exactly this long "
            "without one (s).",
            ge=0,
        ),
    )
    command_ack: str | None = field(
        default=None,
        metadata=described(
            "A Python regex an answer to every init and set_exposure command must match "
            "(none: no answer is read)."
        ),
    )
    #: A refused command fails at once.
    error_reply: str | None = field(
        default=None,
        metadata=described(
            "A Python regex of the line the device sends to refuse a command, e.g. ^ERR."
        ),
    )
    saturated_status: str | None = field(
        default=None,
        metadata=described(
            "A Python regex: a response's status group matching it is a saturated reading."
        ),
    )
    device_averaging: bool = field(
        default=False,
        metadata=described("Send one query with {averages} and let the device average."),
    )
    max_line_bytes: int = field(
        default=1024,
        metadata=described(
            "The longest line read (bytes); longer input is discarded to the line's end.",
            ge=16,
        ),
    )
    stream: SerialStreamConfig | None = field(
        default=None,
        metadata=described(
            "Its streaming mode, for measuring while moving (none: it does not stream)."
        ),
    )

    def __post_init__(self) -> None:
        port = self.port if isinstance(self.port, str) else repr(self.port)

        def bad(message: str) -> SerialDetectorValueError:
            return SerialDetectorValueError(
                f"serial detector {port}: invalid configuration: {message}",
                port=port,
                kind="invalid",
            )

        if not isinstance(self.port, str) or not self.port.strip():
            raise bad("port must be a non-empty string such as '/dev/ttyACM0'")
        baud, retries, max_line = (
            as_int(self.baud),
            as_int(self.retries),
            as_int(self.max_line_bytes),
        )
        timeout, settle = as_real(self.timeout_s), as_real(self.settle_s)
        if baud is None or baud <= 0:
            raise bad(f"baud must be a positive integer, got {self.baud!r}")
        if self.line_ending not in _LINE_ENDINGS:
            raise bad(f"line_ending must be one of {_LINE_ENDINGS!r}, got {self.line_ending!r}")
        if timeout is None or not (0 < timeout < math.inf):
            raise bad(f"timeout_s must be a positive number of seconds, got {self.timeout_s!r}")
        if settle is None or not (0 <= settle < math.inf):
            raise bad(f"settle_s must be ≥ 0 seconds, got {self.settle_s!r}")
        if retries is None or retries < 0:
            raise bad(f"retries must be an integer ≥ 0, got {self.retries!r}")
        full_scale = None if self.full_scale is None else as_real(self.full_scale)
        if self.full_scale is not None and (full_scale is None or not 0 < full_scale < math.inf):
            raise bad(f"full_scale must be a positive number or None, got {self.full_scale!r}")
        if max_line is None or max_line < 16:
            raise bad(f"max_line_bytes must be an integer ≥ 16, got {self.max_line_bytes!r}")
        if isinstance(self.init, str):
            raise bad("init must be a sequence of commands, not one string")
        object.__setattr__(self, "init", tuple(self.init))

        query_fields = _template_fields(self.query, QUERY_FIELDS, "query", bad)
        if self.device_averaging and "averages" not in query_fields:
            raise bad("device_averaging needs an {averages} field in query")
        if self.set_exposure is not None:
            _template_fields(self.set_exposure, EXPOSURE_FIELDS, "set_exposure", bad)
        for command in self.init:
            _template_fields(command, frozenset(), "init command", bad)

        response = _compile(self.response, "response", bad)
        if response is None or "value" not in response.groupindex:
            raise bad(f"response {self.response!r} needs a named group (?P<value>...)")
        for name in ("reset_banner", "command_ack", "error_reply", "saturated_status"):
            _compile(getattr(self, name), name, bad)
        if self.saturated_status is not None and "status" not in response.groupindex:
            raise bad("saturated_status needs a named group (?P<status>...) in response")
        if self.stream is not None:
            if not isinstance(self.stream, SerialStreamConfig):
                raise bad(f"stream must be a SerialStreamConfig or None, got {self.stream!r}")
            self.stream.check(bad)

    @property
    def template_fields(self) -> frozenset[str]:
        """The fields used by ``query`` and ``set_exposure``."""
        fields = _template_fields(self.query, QUERY_FIELDS, "query", _unreachable)
        if self.set_exposure is not None:
            fields |= _template_fields(
                self.set_exposure, EXPOSURE_FIELDS, "set_exposure", _unreachable
            )
        return fields


def as_real(x: object) -> float | None:
    """``x`` as a float if it is a real number (numpy scalars included, bool not)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        return None
    return float(x)


def as_int(x: object) -> int | None:
    """``x`` as an int if it is an integer (numpy integers included, bool not)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        return None
    return int(x)


_BadConfig = Callable[[str], Exception]


def _unreachable(message: str) -> Exception:  # pragma: no cover - validated before
    return AssertionError(message)


def _template_fields(
    template: object,
    allowed: frozenset[str],
    what: str,
    bad: _BadConfig,
    sample_fields: Mapping[str, float | int] = _SAMPLE_FIELDS,
) -> frozenset[str]:
    """The field names of a command template, checked; ``bad(message)`` builds the error."""
    if not isinstance(template, str):
        raise bad(f"{what} must be a string, got {template!r}")
    try:
        names = {name for _, name, _, _ in string.Formatter().parse(template) if name is not None}
    except ValueError as exc:
        raise bad(f"{what} {template!r} is not a valid template: {exc}") from exc
    unknown = names - allowed
    if unknown:
        fields = ", ".join("{" + name + "}" for name in sorted(allowed)) or "none"
        raise bad(f"{what} {template!r} uses {sorted(unknown)}; allowed fields: {fields}")
    try:
        sample = template.format(**sample_fields)
    except (ValueError, TypeError, KeyError, IndexError) as exc:
        raise bad(f"{what} {template!r} cannot be formatted: {exc}") from exc
    if "\r" in sample or "\n" in sample:
        raise bad(f"{what} {template!r} must not contain a line ending")
    if not sample.isascii():
        raise bad(f"{what} {template!r} must be ASCII")
    return frozenset(names)


def _compile(pattern: object, what: str, bad: _BadConfig) -> re.Pattern[str] | None:
    if pattern is None:
        return None
    if not isinstance(pattern, str):
        raise bad(f"{what} must be a regular expression string, got {pattern!r}")
    try:
        return re.compile(pattern)
    except re.error as exc:
        raise bad(f"{what} {pattern!r} is not a valid regular expression: {exc}") from exc
