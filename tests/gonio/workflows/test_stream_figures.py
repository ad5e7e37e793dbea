"""The stream check's rate figures (`gonio.workflows.stream_check.figures`) from
observed lines: a steady stream passes whatever a busy host did to a few arrivals, and
a stream off its rate fails."""

from __future__ import annotations

import numpy as np
import pytest

from drivers.serial_detector import StreamTrace
from gonio.workflows.stream_check.figures import DEFAULT_LIMITS, StreamRecord
from gonio.workflows.stream_check.judge import _steady, _timestamps

RATE_HZ = 100.0


def record(arrivals: np.ndarray, device_t: np.ndarray) -> StreamRecord:
    trace = StreamTrace(
        command="START 100",
        rate_hz=RATE_HZ,
        integration_s=0.01,
        sent_s=0.0,
        start_acknowledged_s=None,
        stop_sent_s=None,
        stop_acknowledged_s=None,
        data_lines=len(arrivals),
        lines_after_ack=0,
        longest_line_bytes=20,
    )
    return StreamRecord(trace, arrivals, device_t)


def stream(rate_hz: float, late_s: dict[int, float], lines: int = 60) -> StreamRecord:
    """``lines`` windows at ``rate_hz`` on the device's clock, each read 2 ms after its
    end, those of ``late_s`` (index → s) that much later."""
    device_t = (np.arange(lines) + 1.0) / rate_hz
    arrivals = device_t + 0.002
    for i, late in late_s.items():
        arrivals[i] += late
    return record(arrivals, device_t)


@pytest.mark.parametrize("late", [{}, {0: 0.0}, {59: 0.012}, {0: 0.012, 59: 0.012, 30: 0.02}])
def test_a_few_lines_read_late_do_not_move_the_rate(late: dict[int, float]) -> None:
    # before: the first-to-last span put 59 gaps in 0.578 s: 102 Hz, failing at 1 %
    steady = _steady([stream(RATE_HZ, late)], 1e-6, DEFAULT_LIMITS)
    assert steady.passed, steady.summary
    assert steady.figures["achieved_hz"] == pytest.approx(RATE_HZ, rel=1e-9)
    stamps = _timestamps([stream(RATE_HZ, late)], True, DEFAULT_LIMITS)
    assert stamps.passed, stamps.summary
    assert stamps.figures["device_to_host_clock"] == pytest.approx(1.0, rel=1e-9)


def test_a_stream_off_its_rate_fails() -> None:
    slow = stream(RATE_HZ * 0.97, {})
    slow = record(slow.received_s, (np.arange(60) + 1.0) / RATE_HZ)  # stamps claim 100 Hz
    steady = _steady([slow], 1e-6, DEFAULT_LIMITS)
    assert not steady.passed and "Hz achieved for 100 Hz asked" in steady.summary
