"""Observing a serial detector's streams for a stream check (the device I/O): one long
stream for the rate, the timestamps and the latency, then short ones for the start and
the stop, each stop followed by a listen for lines that should not come, and a query
once the streams are over. What it saw is judged by `gonio.workflows.stream_check.figures`.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass

import numpy as np

from drivers.serial_detector import SerialDetectorError
from drivers.serial_detector.detector import SerialDetector
from drivers.stream import StreamReading
from gonio.workflows.stream_check.figures import StreamRecord

#: A short stream lasts this many periods, and at least `SHORT_S` (s).
SHORT_PERIODS = 20
SHORT_S = 0.2
#: After a stop, listen this many periods, and at least `LISTEN_S` (s), for late lines.
LISTEN_PERIODS = 5
LISTEN_S = 0.1
#: The longest wait (s) of one read of the stream (the reads return as lines arrive).
READ_S = 0.05


@dataclass(frozen=True)
class Observation:
    """What a stream check saw: the streams (the first the long one), the device's
    answer to the identification command (None: none asked) and the error of the query
    sent after the streams (None: answered)."""

    records: list[StreamRecord]
    identity: str | None
    query_error: str | None


def observe(
    detector: SerialDetector,
    *,
    rate_hz: float,
    duration_s: float,
    starts: int,
    exposure_s: float,
    identify: str | None = None,
) -> Observation:
    """Stream ``starts`` times at ``rate_hz`` (Hz), the first for ``duration_s`` (s),
    then query once at ``exposure_s`` (s). A driver error while opening, asking the
    identity or starting (a port that fails, a refused rate) propagates: nothing was
    measured; one while reading or stopping is a measured failure, kept in the record."""
    stream = detector.config.stream
    if stream is None:
        raise ValueError("a stream check needs a detector configured with a stream section")
    line = re.compile(stream.line)
    identity = None if identify is None else detector.ask(identify)
    records = []
    for k in range(starts):
        seconds = duration_s if k == 0 else max(SHORT_PERIODS / rate_hz, SHORT_S)
        records.append(_one_stream(detector, rate_hz, seconds, line))
    query_error = None
    try:
        detector.measure(exposure_s)
    except SerialDetectorError as exc:
        query_error = str(exc)
    return Observation(records, identity, query_error)


def _one_stream(
    detector: SerialDetector, rate_hz: float, seconds: float, line: re.Pattern[str]
) -> StreamRecord:
    readings: list[StreamReading] = []
    read_error = stop_error = None
    detector.start_stream(rate_hz)
    end = time.monotonic() + seconds
    try:
        while time.monotonic() < end:
            readings += detector.read_stream(READ_S)
    except SerialDetectorError as exc:
        read_error = str(exc)
    try:
        readings += detector.stop_stream()
    except SerialDetectorError as exc:
        stop_error = str(exc)
    trace = detector.last_stream
    assert trace is not None  # a stream was started, and stopped or failed
    heard = detector.listen(max(LISTEN_PERIODS / rate_hz, LISTEN_S))
    return StreamRecord(
        trace=trace,
        received_s=np.array([_or_nan(r.received_s) for r in readings], dtype=np.float64),
        device_t_s=np.array([_or_nan(r.device_t_s) for r in readings], dtype=np.float64),
        data_after_stop=sum(1 for text, _ in heard if line.fullmatch(text)),
        read_error=read_error,
        stop_error=stop_error,
    )


def _or_nan(x: float | None) -> float:
    return float("nan") if x is None else x
