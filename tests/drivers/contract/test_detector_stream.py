"""The streaming rules of the `drivers.base.Detector` contract (`StreamingDetector`), on
every detector backend: those that stream (`STREAMERS`) follow them, the others refuse
to start; a silent stream is tried where the backend can be silenced."""

from __future__ import annotations

import itertools
import math

import pytest

from drivers.errors import DetectorError, DeviceClosed, StreamNotSupported
from drivers.stream import StreamingDetector, StreamReading, can_stream, streaming
from tests.drivers.contract.conftest import INSTRUMENTS, DetectorHarness

RATE_HZ = 200.0
INTEGRATION_S = 0.004
#: How far (s) a window's length may differ from the integration: stamps are floats.
WINDOW_TOLERANCE_S = 1e-9


#: The detector backends that stream; every other one refuses.
STREAMERS = ["sim", "serial"]
#: The backends whose stream a test can silence (the simulated photometer on its pty).
SILENCEABLE = ["serial"]

streamers = pytest.mark.parametrize("detectors", STREAMERS, indirect=True)


def _streamer(detectors: DetectorHarness) -> StreamingDetector:
    det = detectors.make(False)
    assert can_stream(det), f"{detectors.name} should stream"
    return streaming(det)


def _collect(
    det: StreamingDetector, detectors: DetectorHarness, seconds: float
) -> list[StreamReading]:
    readings: list[StreamReading] = []
    end = detectors.clock_now() + seconds
    while detectors.clock_now() < end:
        readings += det.read_stream(0.02)
    return readings


@streamers
def test_a_stream_is_stamped_windows_of_the_integration_at_the_rate(
    detectors: DetectorHarness,
) -> None:
    det = _streamer(detectors)
    with det:
        t0 = detectors.clock_now()
        det.start_stream(RATE_HZ, INTEGRATION_S)
        readings = _collect(det, detectors, 0.3)
        readings += det.stop_stream()
        t1 = detectors.clock_now()
        assert det.stop_stream() == []  # idempotent
        after = det.measure(0.01)  # usable for ordinary reads
    assert not after.saturated and after.value > 0
    duration = t1 - t0
    assert abs(len(readings) - RATE_HZ * duration) <= 0.25 * RATE_HZ * duration + 2
    for r in readings:
        assert t0 <= r.started_s < r.ended_s
        assert r.ended_s - r.started_s == pytest.approx(INTEGRATION_S, abs=WINDOW_TOLERANCE_S)
        assert math.isfinite(r.value) and r.value > 0 and not r.saturated
    for a, b in itertools.pairwise(readings):
        assert b.ended_s > a.ended_s  # stamps increase
        assert b.started_s >= a.ended_s - WINDOW_TOLERANCE_S  # windows do not overlap
    stamped = [r.device_t_s for r in readings if r.device_t_s is not None]
    assert stamped == sorted(stamped)


@streamers
def test_a_stream_refuses_what_it_cannot_do_before_starting(detectors: DetectorHarness) -> None:
    det = _streamer(detectors)
    with pytest.raises(DeviceClosed):
        det.start_stream(RATE_HZ, INTEGRATION_S)
    with det:
        before = detectors.activity()
        for rate, integration in (
            (0.0, None), (-5.0, None), (math.nan, None), (math.inf, None),
            (RATE_HZ, 2 / RATE_HZ), (RATE_HZ, 0.0), (RATE_HZ, -1.0),
        ):  # fmt: skip
            with pytest.raises(DetectorError):
                det.start_stream(rate, integration)
        with pytest.raises(DetectorError):
            det.read_stream()  # no stream running
        assert detectors.activity() == before
        det.start_stream(RATE_HZ, INTEGRATION_S)
        with pytest.raises(DetectorError):
            det.start_stream(RATE_HZ, INTEGRATION_S)  # already running
        with pytest.raises(DetectorError):
            det.measure(0.01)  # not while streaming
        det.stop_stream()
        det.measure(0.01)


@pytest.mark.parametrize("detectors", SILENCEABLE, indirect=True)
def test_a_silent_stream_is_a_detector_error_not_a_hang(detectors: DetectorHarness) -> None:
    assert detectors.silence is not None
    det = _streamer(detectors)
    with det:
        det.start_stream(RATE_HZ, INTEGRATION_S)
        assert det.read_stream(1.0)
        detectors.silence()
        with pytest.raises(DetectorError, match="stream"):
            _collect(det, detectors, 5.0)
        det.stop_stream()  # after a failure: still fine, and idempotent
        det.stop_stream()
    assert not det.is_open


@streamers
def test_closing_a_streaming_detector_releases_it(detectors: DetectorHarness) -> None:
    det = _streamer(detectors)
    with det:
        det.start_stream(RATE_HZ, INTEGRATION_S)
        det.read_stream(0.05)
    assert not det.is_open
    with det:  # reopened: idle, it measures
        assert det.measure(0.01).value > 0


@pytest.mark.parametrize("detectors", list(INSTRUMENTS), indirect=True)
def test_non_streamers_refuse_to_start(detectors: DetectorHarness) -> None:
    det = detectors.make(False)
    assert not can_stream(det)
    with pytest.raises(StreamNotSupported, match="cannot stream"):
        streaming(det)
    if hasattr(det, "start_stream"):
        with det, pytest.raises(StreamNotSupported):
            det.start_stream(RATE_HZ, INTEGRATION_S)
