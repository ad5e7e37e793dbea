"""The serial detector's streaming mode on the simulated photometer over a pty: the
commands on the wire, the stamps, and every way a stream can fail without hanging."""

from __future__ import annotations

import dataclasses
import itertools
import time
from collections.abc import Iterator
from typing import Any

import pytest

from drivers.errors import StreamNotSupported
from drivers.serial_detector import SerialDetectorError
from drivers.serial_detector.detector import SerialDetector
from drivers.stream import StreamReading, can_stream, restamped
from sim.peers.serial_photometer import STREAM_CONFIG, SerialPhotometer

TIMEOUT_S = 0.3


@pytest.fixture
def device() -> Iterator[SerialPhotometer]:
    with SerialPhotometer(20_000.0) as dev:
        yield dev


def streaming_detector(dev: SerialPhotometer, **stream: Any) -> SerialDetector:
    config = dev.config(timeout_s=TIMEOUT_S, stream=dataclasses.replace(STREAM_CONFIG, **stream))
    return SerialDetector(config, exposure_range_s=(1e-3, 10.0))


def collect(det: SerialDetector, seconds: float) -> list[StreamReading]:
    readings: list[StreamReading] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        readings += det.read_stream(0.02)
    return readings


def collect_at_least(det: SerialDetector, n: int, timeout_s: float = 10.0) -> list[StreamReading]:
    """Read until ``n`` readings came (a count, not the host's time: a loaded host may
    run the device's thread late), at most ``timeout_s``."""
    readings: list[StreamReading] = []
    end = time.monotonic() + timeout_s
    while len(readings) < n and time.monotonic() < end:
        readings += det.read_stream(0.02)
    return readings


def test_the_commands_on_the_wire_and_the_values(device: SerialPhotometer) -> None:
    with streaming_detector(device) as det:
        assert device.commands == ["STOP", "GAIN 1"]  # a stream left running is stopped
        det.start_stream(250, 0.002)
        readings = collect(det, 0.2) + det.stop_stream()
        assert not device.streaming
        det.measure(0.01)
    assert device.commands[2:] == ["STREAM 250 2", "STOP", "EXP 10", "MEAS"]
    assert len(readings) == len(device.stream_ends)
    assert all(r.value == pytest.approx(20_000 * 0.002) for r in readings)
    # the device's timestamps, in its milliseconds, end windows one period apart
    device_t = [r.device_t_s for r in readings if r.device_t_s is not None]
    assert len(device_t) == len(readings)
    assert all(b - a == pytest.approx(0.004, abs=2e-6) for a, b in itertools.pairwise(device_t))
    truth = device.stream_ends
    again = restamped(readings)
    assert max(abs(r.ended_s - t) for r, t in zip(again, truth, strict=True)) < 0.02
    assert [r.ended_s - r.started_s for r in again] == pytest.approx([0.002] * len(again))


def test_without_device_timestamps_the_arrival_stamps_the_window(
    device: SerialPhotometer,
) -> None:
    with streaming_detector(device, line=r"DAT \S+ (?P<value>\S+) (?P<status>OK|SAT)") as det:
        det.start_stream(100, 0.005)
        readings = collect(det, 0.15) + det.stop_stream()
    assert readings and all(r.device_t_s is None for r in readings)
    assert all(r.received_s is not None and r.ended_s <= r.received_s for r in readings)


def test_the_integration_is_rounded_as_the_template_sends_it(device: SerialPhotometer) -> None:
    with streaming_detector(device) as det:
        det.start_stream(600)  # the period 1.667 ms: 1 ms, never rounded past the period
        readings = collect(det, 0.05) + det.stop_stream()
    assert "STREAM 600 1" in device.commands
    assert readings[0].ended_s - readings[0].started_s == pytest.approx(0.001)


def test_refused_before_anything_is_sent(device: SerialPhotometer) -> None:
    with streaming_detector(device, max_rate_hz=500.0) as det:
        sent = len(device.commands)
        for rate, integration in ((501.0, None), (100.0, 0.02), (100.0, 1e-4)):
            with pytest.raises(SerialDetectorError, match=device.path) as err:
                det.start_stream(rate, integration)
            assert err.value.kind == "invalid"
        assert len(device.commands) == sent


def test_without_a_stream_section_it_cannot_stream(device: SerialPhotometer) -> None:
    with SerialDetector(device.config()) as det:
        assert not can_stream(det)
        with pytest.raises(StreamNotSupported, match=f"serial detector {device.path}"):
            det.start_stream(100)


@pytest.mark.parametrize(
    ("fault", "kind"),
    [("silent", "timeout"), ("malformed", "malformed"), ("garbage", "malformed")],
)
def test_a_failing_stream_is_one_error_naming_the_port_then_the_device_measures(
    device: SerialPhotometer, fault: str, kind: str
) -> None:
    with streaming_detector(device) as det:
        det.start_stream(200, 0.002)
        assert det.read_stream(1.0)
        if fault == "silent":
            device.silent()
        elif fault == "malformed":
            device.malformed(5)
        else:
            device.garbage_without_newline(2000)  # an overlong line, then more garbage
            device.malformed(5)
        start = time.monotonic()
        with pytest.raises(SerialDetectorError, match=device.path) as err:
            collect(det, 3.0)
        # the stall is found after the timeout, not when the reading gives up (3 s)
        assert time.monotonic() - start < TIMEOUT_S + 1.5
        assert err.value.kind in (kind, "overflow")
        assert det.stop_stream() == []
        device.clear()
        assert det.measure(0.01).value == pytest.approx(200.0)
        assert not device.streaming


def test_a_few_stray_lines_are_tolerated(device: SerialPhotometer) -> None:
    with streaming_detector(device) as det:
        det.start_stream(200, 0.002)
        device.malformed(2)  # retries = 2: two in a row are tolerated
        readings = collect_at_least(det, 10) + det.stop_stream()
    assert len(readings) >= 10


def test_a_reset_mid_stream_is_a_reset_error(device: SerialPhotometer) -> None:
    with streaming_detector(device) as det:
        det.start_stream(200, 0.002)
        det.read_stream(1.0)
        device.reboot()
        with pytest.raises(SerialDetectorError, match="reset") as err:
            collect(det, 2.0)
        assert err.value.kind == "reset"
        assert det.measure(0.01).value == pytest.approx(200.0)  # re-initialized


def test_measure_during_a_stream_is_refused(device: SerialPhotometer) -> None:
    with streaming_detector(device) as det:
        det.start_stream(100)
        with pytest.raises(SerialDetectorError, match="stop_stream first") as err:
            det.measure(0.01)
        assert err.value.kind == "streaming"


def test_a_stream_left_running_is_stopped_when_the_port_opens(device: SerialPhotometer) -> None:
    det = streaming_detector(device)
    det.open()
    det.start_stream(200, 0.002)
    assert det.read_stream(1.0)
    det._release()  # a killed run: the port goes, the device keeps streaming
    assert device.streaming
    with streaming_detector(device) as again:
        assert not device.streaming
        assert again.measure(0.01).value == pytest.approx(200.0)


def test_the_simulated_photometer_reads_its_signal_at_each_window_middle() -> None:
    calls: list[float] = []

    def signal(exposure_s: float) -> float:
        calls.append(time.monotonic())
        return 100.0

    with SerialPhotometer(signal) as dev, streaming_detector(dev) as det:
        det.start_stream(50, 0.01)
        readings = collect_at_least(det, 12) + det.stop_stream()
        ends = dev.stream_ends
    n = min(len(calls), len(ends), len(readings))
    assert n >= 10
    late = [c - (e - 0.005) for c, e in zip(calls[:n], ends[:n], strict=True)]
    # never before the middle; a loaded host may run the device's thread late, so the
    # bound on time is the best window's, and every window is read before its line left
    assert min(late) > -1e-3
    assert min(late) < 2.5e-3
    received = [r.received_s for r in readings[:n]]
    assert all(s is not None and c < s for c, s in zip(calls[:n], received, strict=True))


def test_a_device_that_starts_on_the_command_is_stamped_from_it(
    device: SerialPhotometer,
) -> None:
    """``starts_on_command``: the first window began when the command arrived, between
    when it left and when its acknowledgement came back (awaited by ``start_stream``):
    each stamp is within those bounds of the truth, the stop's acknowledgement ends the
    stream, every window the device sent received."""
    with streaming_detector(device, starts_on_command=True) as det:
        det.start_stream(250, 0.002)
        readings = collect(det, 0.1) + det.stop_stream()
        trace = det.last_stream
        det.measure(0.01)  # idle again
    truth = device.stream_ends
    assert len(readings) == len(truth) and trace is not None
    assert trace.start_acknowledged_s is not None
    round_trip = trace.start_acknowledged_s - trace.sent_s
    early = [r.ended_s - t for r, t in zip(readings, truth, strict=True)]
    assert min(early) >= -1e-6 and max(early) <= round_trip + 1e-6
    # the bound each reading states lies below the truth and the stamp (not before the
    # command left)
    for r, t in zip(readings, truth, strict=True):
        assert r.earliest_end_s is not None
        assert r.earliest_end_s - 1e-6 <= min(t, r.ended_s)


def test_a_device_slow_to_take_the_start_is_stamped_from_its_acknowledgement(
    device: SerialPhotometer,
) -> None:
    """A device that takes the start command 20 ms after it arrived (its loop busy)
    begins its first window then, and acknowledges it then: the stamps follow the
    acknowledgement, not the command's departure (which would put every window 20 ms
    early)."""
    with streaming_detector(device, starts_on_command=True) as det:
        device.late(0.02)
        det.start_stream(250, 0.002)
        readings = collect_at_least(det, 12) + det.stop_stream()
        trace = det.last_stream
    truth = device.stream_ends
    assert len(readings) == len(truth) >= 10 and trace is not None
    assert trace.start_acknowledged_s is not None
    round_trip = trace.start_acknowledged_s - trace.sent_s
    assert round_trip >= 0.02
    early = [r.ended_s - t for r, t in zip(readings, truth, strict=True)]
    # at most the acknowledgement's way back (the round trip less the 20 ms it waited)
    assert min(early) >= -1e-6 and max(early) <= round_trip - 0.02 + 1e-6
