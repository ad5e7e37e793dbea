"""What the serial detector records of a stream's conversation (`StreamTrace`), its
``ask`` and ``listen``, against the simulated photometer (with its stream quirks) on a pty."""

from __future__ import annotations

import dataclasses
import time

import pytest

from drivers.serial_detector import SerialDetectorError
from drivers.serial_detector.detector import SerialDetector
from sim.peers.serial_photometer import IDENTITY, STREAM_CONFIG, SerialPhotometer, StreamQuirks


def detector(dev: SerialPhotometer, **stream: object) -> SerialDetector:
    config = dev.config(timeout_s=0.3, stream=dataclasses.replace(STREAM_CONFIG, **stream))
    return SerialDetector(config, exposure_range_s=(1e-3, 10.0))


def test_the_trace_of_a_conforming_stream() -> None:
    with SerialPhotometer(20_000.0) as dev, detector(dev) as det:
        assert det.last_stream is None
        before = time.monotonic()
        det.start_stream(200, 0.005)
        readings = det.read_stream(0.5)
        end = time.monotonic() + 0.1
        while time.monotonic() < end:
            readings += det.read_stream(0.02)
        readings += det.stop_stream()
        trace = det.last_stream
        assert det.ask("ID?") == IDENTITY
        assert det.listen(0.05) == []
    assert trace is not None and trace.command == "STREAM 200 5"
    assert (trace.rate_hz, trace.integration_s) == (200, 0.005)
    assert trace.start_acknowledged_s is not None and trace.stop_acknowledged_s is not None
    assert trace.stop_sent_s is not None
    assert before <= trace.sent_s < trace.start_acknowledged_s
    first = readings[0].received_s
    assert first is not None and trace.start_acknowledged_s <= first
    assert trace.sent_s < trace.stop_sent_s < trace.stop_acknowledged_s
    assert trace.data_lines == len(readings) and trace.lines_after_ack == 0
    # "DAT <t_ms> <counts> OK": the counts of 5 ms at 20 000 counts/s are 100.0
    assert trace.longest_line_bytes == max(
        len(f"DAT {r.device_t_s * 1000:.3f} 100.0 OK")  # type: ignore[operator]
        for r in readings
    )


def test_lines_after_the_stop_acknowledgement_are_seen() -> None:
    quirks = StreamQuirks(lines_after_stop_ack=3)
    with SerialPhotometer(20_000.0, quirks=quirks) as dev, detector(dev) as det:
        det.start_stream(100, 0.005)
        det.read_stream(0.5)
        det.stop_stream()
        trace = det.last_stream
        # the device's thread sends them at its own pace: a loaded host may run it late
        heard = det.listen(0.5)
    assert trace is not None and trace.stop_acknowledged_s is not None
    late = trace.lines_after_ack + sum(text.startswith("DAT ") for text, _ in heard)
    assert late == 3


def test_a_stop_never_acknowledged_is_traced_without_its_acknowledgement() -> None:
    quirks = StreamQuirks(stop_ack_delay_s=None)
    with SerialPhotometer(20_000.0, quirks=quirks) as dev, detector(dev) as det:
        det.start_stream(100, 0.005)
        det.read_stream(0.5)
        with pytest.raises(SerialDetectorError, match="did not acknowledge 'STOP'"):
            det.stop_stream()
        trace = det.last_stream
    assert trace is not None and trace.stop_sent_s is not None
    assert trace.stop_acknowledged_s is None


def test_ask_and_listen_refuse_during_a_stream_and_bad_commands() -> None:
    with SerialPhotometer(20_000.0) as dev, detector(dev) as det:
        with pytest.raises(SerialDetectorError, match="must not contain a line ending"):
            det.ask("ID?\nMEAS")
        det.start_stream(100, 0.005)
        with pytest.raises(SerialDetectorError, match="during a stream") as info:
            det.ask("ID?")
        assert info.value.kind == "streaming"
        with pytest.raises(SerialDetectorError, match="during a stream"):
            det.listen(0.01)
        det.stop_stream()
        with pytest.raises(SerialDetectorError, match="refused 'NOPE'"):
            det.ask("NOPE")
