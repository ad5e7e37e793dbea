"""The serial detector driver against the simulated photometer on a real pseudo-terminal.

Every test goes through the tty byte by byte (pyserial on one side, the simulator on
the other); failure tests also assert how long the driver took to give up, in a way a
busy shared machine cannot fail: a deadline the driver must wait out is bounded on both
sides (`waited_out`), and a path that must not wait is given a deadline so long
(`PATIENT_S`) that waiting it out could not pass for scheduling noise.
"""

from __future__ import annotations

import _thread
import errno
import math
import os
import statistics
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
import serial

from drivers.errors import DetectorError, DriverError
from drivers.serial_detector import (
    SerialDetectorConfig,
    SerialDetectorError,
    SerialDetectorValueError,
)
from drivers.serial_detector.detector import SerialDetector
from drivers.values import Reading
from sim.peers.serial_photometer import MALFORMED_LINE, SerialPhotometer, default_config

TIMEOUT_S = 0.2  # the per-line margin used throughout: deadlines are exposure + this
EXPOSURE_S = 0.01
#: The margin of a detector that must fail (or answer) without waiting out its deadline.
PATIENT_S = 5.0


def waited_out(elapsed: float, deadline: float) -> bool:
    """The driver gave up at its deadline: at least ``deadline`` (the behaviour), at most
    ``deadline`` × 3 + 1 s (only a guard against hanging: a busy machine adds time)."""
    return deadline <= elapsed <= 3 * deadline + 1.0


def sequence(*values: float) -> Callable[[float], float]:
    """A signal returning ``values`` one after the other, whatever the exposure."""
    it = iter(values)
    return lambda _exposure_s: next(it)


@pytest.fixture
def device() -> Iterator[SerialPhotometer]:
    with SerialPhotometer(20_000.0) as dev:
        yield dev


def config_for(dev: SerialPhotometer, **overrides: Any) -> SerialDetectorConfig:
    overrides.setdefault("timeout_s", TIMEOUT_S)
    return dev.config(**overrides)


@pytest.fixture
def detector(device: SerialPhotometer) -> Iterator[SerialDetector]:
    """An open detector that has taken one reading at ``EXPOSURE_S``; the device's
    command log starts empty."""
    with SerialDetector(config_for(device)) as det:
        det.measure(EXPOSURE_S)
        device.clear_commands()
        yield det


@pytest.fixture
def patient(device: SerialPhotometer) -> Iterator[SerialDetector]:
    """As `detector`, but with a ``PATIENT_S`` margin: a failure it reports well before
    that deadline did not wait for it."""
    with SerialDetector(config_for(device, timeout_s=PATIENT_S)) as det:
        det.measure(EXPOSURE_S)
        device.clear_commands()
        yield det


def timed(fn: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.monotonic()
    result = fn()
    return result, time.monotonic() - t0


def failing(fn: Callable[[], Any]) -> tuple[SerialDetectorError, float]:
    t0 = time.monotonic()
    with pytest.raises(SerialDetectorError) as info:
        fn()
    return info.value, time.monotonic() - t0


# -- happy path -------------------------------------------------------------------------


def test_reading_and_the_commands_on_the_wire(device: SerialPhotometer) -> None:
    with SerialDetector(config_for(device)) as det:
        reading = det.measure(EXPOSURE_S)
    assert reading == Reading(
        value=200.0, std=0.0, n=1, saturated=False, started_s=reading.started_s,
        ended_s=reading.ended_s, raw=(200.0,),
    )  # fmt: skip
    assert reading.ended_s - reading.started_s >= EXPOSURE_S
    assert device.commands == ["GAIN 1", "EXP 10", "MEAS"]  # init on open, then exposure


@pytest.mark.parametrize(
    "values", [(1.0, 2.0, 3.0, 4.0), (10.0, 12.5, 9.0, 11.0, 13.25), (7.0, 7.0)]
)
def test_host_averaging_statistics(values: tuple[float, ...]) -> None:
    with (
        SerialPhotometer(sequence(*values)) as dev,
        SerialDetector(config_for(dev)) as det,
    ):
        reading = det.measure(0.002, averages=len(values))
        assert dev.commands.count("MEAS") == len(values)
    assert reading.n == len(values)
    assert reading.raw == values
    assert reading.value == pytest.approx(statistics.fmean(values))
    assert reading.std == pytest.approx(statistics.stdev(values))
    assert not reading.saturated


def test_device_averaging_one_query_and_a_deadline_covering_every_exposure() -> None:
    values = (1.0, 2.0, 3.0, 4.0)
    with SerialPhotometer(sequence(*values)) as dev:
        cfg = config_for(
            dev,
            query="MEAS {exposure_ms:d} {averages:d}",
            device_averaging=True,
            set_exposure=None,
        )
        with SerialDetector(cfg) as det:
            # 4 × 0.1 s on the device: longer than one exposure plus the margin
            reading, elapsed = timed(lambda: det.measure(0.1, averages=4))
        assert dev.commands == ["GAIN 1", "MEAS 100 4"]
    assert elapsed >= 0.4
    assert reading.n == 4
    assert reading.value == pytest.approx(2.5)
    assert reading.std == pytest.approx(statistics.stdev(values))
    assert reading.raw == (pytest.approx(2.5),)


def test_device_averaging_without_a_reported_std_gives_nan(device: SerialPhotometer) -> None:
    cfg = config_for(
        device, query="MEAS {exposure_ms:d} {averages:d}", device_averaging=True, set_exposure=None
    )
    with SerialDetector(cfg) as det:
        reading = det.measure(EXPOSURE_S, averages=1)  # the device omits std for n = 1
    assert reading.value == 200.0
    assert math.isnan(reading.std)


def test_exposure_command_sent_only_when_it_changes(
    device: SerialPhotometer, detector: SerialDetector
) -> None:
    values = [detector.measure(e).value for e in (0.01, 0.01, 0.02, 0.02, 0.0201, 0.01)]
    assert values == [200.0, 200.0, 400.0, 400.0, 400.0, 200.0]  # 20.1 ms rounds to 20
    exposures = [c for c in device.commands if c.startswith("EXP")]
    assert exposures == ["EXP 20", "EXP 10"]  # EXP 10 was sent by the fixture's reading
    assert device.exposure_ms == 10


def test_a_reading_says_the_exposure_the_device_integrated(
    device: SerialPhotometer, detector: SerialDetector
) -> None:
    """Templates in whole milliseconds round what is asked: the reading says so (the
    engine journals it), and says nothing when the device integrated what was asked."""
    assert detector.measure(0.0201).exposure_s == 0.02
    assert detector.measure(0.0015625).exposure_s == 0.002
    assert detector.measure(0.01).exposure_s is None


def test_exposure_in_the_query_template(device: SerialPhotometer) -> None:
    cfg = config_for(device, query="MEAS {exposure_ms:d}", set_exposure=None)
    with SerialDetector(cfg) as det:
        assert det.measure(0.025).value == 500.0
        assert det.measure(0.005).value == 100.0
    assert device.commands == ["GAIN 1", "MEAS 25", "MEAS 5"]


def test_echoing_device() -> None:
    with SerialPhotometer(20_000.0, echo=True) as dev, SerialDetector(config_for(dev)) as det:
        assert det.measure(EXPOSURE_S).value == 200.0
        assert det.measure(EXPOSURE_S, averages=3).raw == (200.0, 200.0, 200.0)


def test_numpy_arguments_are_accepted(detector: SerialDetector) -> None:
    reading = detector.measure(np.float64(0.01), averages=np.int64(2))  # type: ignore[arg-type]
    assert reading.n == 2
    assert reading.value == 200.0


# -- saturation ---------------------------------------------------------------------------


def test_saturation_from_full_scale() -> None:
    with SerialPhotometer(sequence(999.0, 1000.0, 10.0), full_scale=None) as dev:
        cfg = config_for(
            dev,
            response=r"VAL (?P<value>\S+) \w+(?: \S+)?",
            saturated_status=None,
            full_scale=1000.0,
        )
        with SerialDetector(cfg) as det:
            assert not det.measure(EXPOSURE_S).saturated
            assert det.measure(EXPOSURE_S).saturated  # ≥ full scale
            assert not det.measure(EXPOSURE_S).saturated


@pytest.mark.parametrize(
    "overrides",
    [
        {},  # (?P<status>OK|SAT) with saturated_status "^SAT$"
        {"response": r"VAL (?P<value>\S+) (?:OK|(?P<saturated>SAT))", "saturated_status": None},
    ],
    ids=["status-group", "saturated-group"],
)
def test_saturation_from_the_device(overrides: dict[str, Any]) -> None:
    # the device clips at 100 counts and says SAT; the driver has no full scale
    with (
        SerialPhotometer(sequence(50.0, 150.0, 50.0, 60.0), full_scale=100.0) as dev,
        SerialDetector(config_for(dev, **overrides)) as det,
    ):
        mixed = det.measure(EXPOSURE_S, averages=3)
        clean = det.measure(EXPOSURE_S)
    assert mixed.saturated
    assert mixed.raw == (50.0, 100.0, 50.0)
    assert not clean.saturated


@pytest.mark.parametrize(
    ("flag", "saturated"),
    [("0", False), ("1", True), ("no", False), ("yes", True), ("off", False), ("SAT", True)],
)
def test_saturated_group_false_words(device: SerialPhotometer, flag: str, saturated: bool) -> None:
    cfg = config_for(
        device, response=r"VAL (?P<value>\S+) (?P<saturated>\w+)", saturated_status=None
    )
    with SerialDetector(cfg) as det:
        device.inject(f"VAL 5 {flag}")
        assert det.measure(EXPOSURE_S).saturated is saturated


# -- malformed lines ----------------------------------------------------------------------


def test_malformed_line_then_success(device: SerialPhotometer, detector: SerialDetector) -> None:
    device.malformed(1)
    reading, elapsed = timed(lambda: detector.measure(EXPOSURE_S))
    assert reading.value == 200.0
    assert device.commands == ["MEAS", "MEAS"]  # asked again once the deadline passed
    assert waited_out(elapsed, EXPOSURE_S + TIMEOUT_S)


def test_stray_line_before_the_answer_costs_nothing(
    device: SerialPhotometer, patient: SerialDetector
) -> None:
    device.slow(0.1)
    timer = threading.Timer(0.03, device.unsolicited, ("debug: adc ok",))
    timer.start()
    try:
        reading, elapsed = timed(lambda: patient.measure(EXPOSURE_S))
    finally:
        timer.join()
    assert reading.value == 200.0
    assert device.commands == ["MEAS"]  # the stray line did not make it ask again
    assert 0.1 <= elapsed < PATIENT_S  # nor wait out the deadline: the answer ended it


def test_too_many_malformed_lines_quote_the_line(
    device: SerialPhotometer, detector: SerialDetector
) -> None:
    # retries = 2: three answers, two deadlines waited out, the third fails at once —
    # before the good line that follows it on the wire (listening on would take it).
    device.inject(MALFORMED_LINE, MALFORMED_LINE, f"{MALFORMED_LINE}\r\nVAL 5 OK")
    error, elapsed = failing(lambda: detector.measure(EXPOSURE_S))
    assert error.kind == "malformed"
    assert error.line == MALFORMED_LINE
    assert repr(MALFORMED_LINE) in str(error)
    assert detector.port in str(error)
    assert "\n" not in str(error)
    assert device.commands == ["MEAS"] * 3
    assert waited_out(elapsed, 2 * (EXPOSURE_S + TIMEOUT_S))
    device.clear()
    assert detector.measure(EXPOSURE_S).value == 200.0


def test_no_retries_fail_at_the_first_malformed_line(device: SerialPhotometer) -> None:
    with SerialDetector(config_for(device, retries=0)) as det:
        # matches the pattern, but is not a number; the good line after it is not heard
        device.inject("VAL 1.2.3 OK\r\nVAL 5 OK")
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
    assert error.kind == "malformed"
    assert "'VAL 1.2.3 OK'" in str(error)
    assert device.commands == ["GAIN 1", "EXP 10", "MEAS"]


def test_long_lines_are_truncated_in_the_message(device: SerialPhotometer) -> None:
    with SerialDetector(config_for(device, retries=0)) as det:
        device.inject("X" * 500)
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
    assert len(str(error)) < 300
    assert "(500 characters)" in str(error)


@pytest.mark.parametrize("text", ["nan", "NaN", "inf", "-inf", "1e999", "Infinity"])
def test_non_finite_values_fail_without_retry(
    device: SerialPhotometer, patient: SerialDetector, text: str
) -> None:
    device.inject(f"VAL {text} OK\r\nVAL 5 OK")  # failing at once, the good line is not heard
    error, elapsed = failing(lambda: patient.measure(EXPOSURE_S))
    assert error.kind == "value"
    assert f"'VAL {text} OK'" in str(error)
    assert device.commands == ["MEAS"]
    assert elapsed < PATIENT_S
    assert patient.measure(EXPOSURE_S).value == 200.0


def test_device_error_reply_fails_at_once(device: SerialPhotometer) -> None:
    with SerialDetector(config_for(device, query="MEASURE", timeout_s=PATIENT_S)) as det:
        error, elapsed = failing(lambda: det.measure(EXPOSURE_S))
    assert error.kind == "device"
    assert "refused 'MEASURE'" in str(error)
    assert "ERR unknown command" in str(error)
    assert device.commands == ["GAIN 1", "EXP 10", "MEASURE"]  # asked once
    assert elapsed < PATIENT_S


# -- silence, slowness, resets, garbage -----------------------------------------------------


def test_silent_device_fails_within_the_deadline(
    device: SerialPhotometer, detector: SerialDetector
) -> None:
    detector.measure(0.05)  # the exposure is set: only the query goes unanswered
    device.silent()
    error, elapsed = failing(lambda: detector.measure(0.05))
    assert error.kind == "timeout"
    assert "no answer to 'MEAS' within 0.25 s" in str(error)
    assert waited_out(elapsed, 0.05 + TIMEOUT_S)
    device.clear()
    assert detector.measure(EXPOSURE_S).value == 200.0


def test_slow_device_within_the_margin(device: SerialPhotometer, detector: SerialDetector) -> None:
    device.slow(TIMEOUT_S / 2)
    assert detector.measure(EXPOSURE_S).value == 200.0


def test_late_answer_is_never_taken_for_the_next_one() -> None:
    with SerialPhotometer(sequence(1.0, 2.0, 3.0)) as dev, SerialDetector(config_for(dev)) as det:
        assert det.measure(EXPOSURE_S).value == 1.0
        dev.slow(TIMEOUT_S + 0.1)  # the answer "2" arrives 0.1 s after the deadline
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
        assert error.kind == "timeout"
        dev.clear()
        assert det.measure(EXPOSURE_S).value == 3.0  # not the late 2.0


def test_an_answer_later_than_a_quiet_spell_is_never_taken_for_the_next_one() -> None:
    """The late answer comes after the line has been quiet for ``timeout_s`` past the
    failed query's deadline (listening out the line alone would then have let it in):
    the resync's acknowledged command marks the end of what the device still owed."""
    with (
        SerialPhotometer(sequence(1.0, 2.0, 3.0, 4.0)) as dev,
        SerialDetector(config_for(dev)) as det,
    ):
        assert det.measure(EXPOSURE_S).value == 1.0
        dev.late(2.5 * TIMEOUT_S)  # the answer 2.0, and everything behind it
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
        assert error.kind == "timeout"
        dev.clear_commands()
        assert det.measure(EXPOSURE_S).value == 3.0  # not the late 2.0
        assert det.resynced_away == 1  # the late 2.0, before the acknowledgement
        assert dev.commands[-1] == "MEAS"
        assert set(dev.commands[:-1]) == {"EXP 10"}  # the resync first
        assert det.measure(EXPOSURE_S).value == 4.0
        assert det.resynced_away == 1


def test_a_resync_without_an_acknowledgement_fails_and_is_tried_again() -> None:
    with SerialPhotometer(sequence(1.0, 2.0, 3.0)) as dev, SerialDetector(config_for(dev)) as det:
        assert det.measure(EXPOSURE_S).value == 1.0
        dev.late(6 * TIMEOUT_S)  # past the query's deadline and the resync's 3 × timeout_s
        assert failing(lambda: det.measure(EXPOSURE_S))[0].kind == "timeout"
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
        assert error.kind == "timeout" and "resynchronizing" in str(error)
        assert det.measure(EXPOSURE_S).value == 3.0  # the late 2.0 was discarded
        assert det.resynced_away >= 1


def test_ctrl_c_during_a_reading_then_the_late_answer_is_discarded() -> None:
    with SerialPhotometer(sequence(1.0, 2.0, 3.0)) as dev, SerialDetector(config_for(dev)) as det:
        assert det.measure(EXPOSURE_S).value == 1.0
        dev.slow(0.15)  # the answer "2" comes 0.16 s after the query
        timer = threading.Timer(0.05, _thread.interrupt_main)
        timer.start()
        try:
            with pytest.raises(KeyboardInterrupt):
                det.measure(EXPOSURE_S)
        finally:
            timer.join()
        assert det.is_open  # caught outside the context manager: still open
        dev.clear()
        assert det.measure(EXPOSURE_S).value == 3.0


def test_reset_mid_read_then_reinitialized(
    device: SerialPhotometer, patient: SerialDetector
) -> None:
    patient.measure(0.02)  # the device's exposure is now 20 ms
    device.reset_mid_read()
    error, elapsed = failing(lambda: patient.measure(0.02))
    assert error.kind == "reset"
    assert "reset during a reading" in str(error)
    assert error.line is not None and error.line.startswith("READY")
    assert elapsed < PATIENT_S  # the banner ended the wait, not the deadline
    assert patient.resets == 1
    assert device.exposure_ms == 10  # the reset forgot it
    device.clear_commands()
    assert patient.measure(0.02).value == 400.0
    assert device.commands == ["GAIN 1", "EXP 20", "MEAS"]  # init and exposure sent again


def test_reset_between_readings_is_noticed_and_recovered(
    device: SerialPhotometer, detector: SerialDetector
) -> None:
    detector.measure(0.02)
    device.reboot()
    time.sleep(0.02)  # the banner is waiting in the input when the next reading starts
    device.clear_commands()
    assert detector.measure(0.02).value == 400.0
    assert device.commands == ["GAIN 1", "EXP 20", "MEAS"]
    assert detector.resets == 1


def test_garbage_without_newline_is_bounded_and_an_error(device: SerialPhotometer) -> None:
    """The overflow fails the reading, holds nothing beyond the limit, and the detector
    recovers (the next reading listens the garbage out, for its timeout); a patient
    detector shows that the overflow ends the wait at once."""
    with SerialDetector(config_for(device, retries=0, max_line_bytes=256)) as det:
        device.garbage_without_newline(100_000)
        error, _ = failing(lambda: det.measure(EXPOSURE_S))
        assert error.kind == "overflow"
        assert "longer than 256 bytes" in str(error)
        assert "'0123456789" in str(error)
        assert det._io.pending <= 256  # nothing held beyond the limit
        assert det.measure(EXPOSURE_S).value == 200.0  # and it recovers
    cfg = config_for(device, retries=0, max_line_bytes=256, timeout_s=PATIENT_S)
    with SerialDetector(cfg) as det:
        device.garbage_without_newline(100_000)
        error, elapsed = failing(lambda: det.measure(EXPOSURE_S))
        assert error.kind == "overflow"
        assert elapsed < PATIENT_S  # the overflow ended the wait, not the deadline


def test_garbage_then_a_retry_succeeds(device: SerialPhotometer, detector: SerialDetector) -> None:
    device.garbage_without_newline(50_000)
    reading, elapsed = timed(lambda: detector.measure(EXPOSURE_S))
    assert reading.value == 200.0
    assert device.commands == ["MEAS", "MEAS"]  # one deadline waited out, then asked again
    assert waited_out(elapsed, EXPOSURE_S + TIMEOUT_S)


# -- the port -----------------------------------------------------------------------------


def test_missing_port() -> None:
    det = SerialDetector(SerialDetectorConfig(port="/dev/does-not-exist", timeout_s=PATIENT_S))
    error, elapsed = failing(det.__enter__)
    assert error.kind == "open"
    assert str(error).startswith("serial detector /dev/does-not-exist: cannot open the port")
    assert "no such device" in str(error)
    assert not det.is_open
    assert elapsed < PATIENT_S  # refused at once, not waited for
    assert isinstance(error, DetectorError) and isinstance(error, DriverError)


def test_busy_port(device: SerialPhotometer, detector: SerialDetector) -> None:
    error, _ = failing(SerialDetector(config_for(device)).open)
    assert error.kind == "open"
    assert "busy" in str(error)
    assert detector.measure(EXPOSURE_S).value == 200.0  # the first owner is unaffected


def test_permission_denied_names_the_reason(
    monkeypatch: pytest.MonkeyPatch, device: SerialPhotometer
) -> None:
    def refuse(url: str, **_: Any) -> None:
        raise serial.SerialException(errno.EACCES, f"could not open port {url}: denied")

    monkeypatch.setattr(serial, "serial_for_url", refuse)
    error, _ = failing(SerialDetector(config_for(device)).open)
    assert "permission denied" in str(error)
    assert "dialout" in str(error)


@pytest.mark.skipif(os.geteuid() == 0, reason="root is never denied")
def test_permission_denied_for_real(tmp_path: Any) -> None:  # pragma: no cover - not root
    port = tmp_path / "ttyFAKE"
    port.touch(mode=0)
    error, _ = failing(SerialDetector(SerialDetectorConfig(port=str(port))).open)
    assert "permission denied" in str(error)


def test_unknown_url_scheme() -> None:
    error, _ = failing(SerialDetector(SerialDetectorConfig(port="nope://x")).open)
    assert error.kind == "open"
    assert "nope" in str(error)


@pytest.mark.parametrize("exception", [RuntimeError, KeyboardInterrupt])
def test_port_closed_on_exception_inside_the_context(
    device: SerialPhotometer, exception: type[BaseException]
) -> None:
    det = SerialDetector(config_for(device))

    def fail_inside() -> None:
        with det:
            det.measure(EXPOSURE_S)
            raise exception("boom")

    with pytest.raises(exception):
        fail_inside()
    assert not det.is_open
    with SerialDetector(config_for(device)) as again:  # the exclusive lock is free at once
        assert again.measure(EXPOSURE_S).value == 200.0


def test_port_closed_when_a_reading_fails_inside_the_context(device: SerialPhotometer) -> None:
    det = SerialDetector(config_for(device))
    device.silent()
    with pytest.raises(SerialDetectorError), det:
        det.measure(EXPOSURE_S)
    assert not det.is_open
    device.clear()
    with SerialDetector(config_for(device)) as again:
        assert again.measure(EXPOSURE_S).value == 200.0


def test_failed_initialization_releases_the_port(device: SerialPhotometer) -> None:
    device.silent()
    det = SerialDetector(config_for(device))
    error, elapsed = failing(det.open)
    assert error.kind == "timeout"
    assert "no acknowledgement to 'GAIN 1'" in str(error)
    assert waited_out(elapsed, TIMEOUT_S)
    assert not det.is_open
    device.clear()
    with det:  # opens again, lock free
        assert det.measure(EXPOSURE_S).value == 200.0


def test_open_and_close_are_idempotent(device: SerialPhotometer) -> None:
    det = SerialDetector(config_for(device))
    det.open()
    det.open()
    assert det.measure(EXPOSURE_S).value == 200.0
    det.close()
    det.close()
    error, _ = failing(lambda: det.measure(EXPOSURE_S))
    assert error.kind == "closed"
    assert "not open" in str(error)


def test_unplugged_device_releases_the_port_and_reopens_on_the_next_call() -> None:
    dev = SerialPhotometer(20_000.0)
    dev.start()
    try:
        with SerialDetector(config_for(dev, timeout_s=PATIENT_S)) as det:
            assert det.measure(EXPOSURE_S).value == 200.0
            dev.stop()  # the pty goes away, as a USB adapter does when pulled
            error, elapsed = failing(lambda: det.measure(EXPOSURE_S))
            assert error.kind == "io"
            assert "released" in str(error)
            assert not det.is_open
            assert elapsed < PATIENT_S  # noticed at once, not at the deadline
            error, _ = failing(lambda: det.measure(EXPOSURE_S))  # tries to reopen
            assert error.kind == "open"
    finally:
        dev.stop()


def test_settle_waits_for_the_banner_after_an_arduino_style_reset_on_open() -> None:
    with SerialPhotometer(20_000.0, reset_on_open=True, boot_s=0.15) as dev:
        det = SerialDetector(config_for(dev, settle_s=2.0))
        _, elapsed = timed(det.open)
        with det:
            assert det.measure(EXPOSURE_S).value == 200.0
        assert 0.15 <= elapsed < 2.0  # the banner ended the wait, not settle_s


def test_without_settling_a_booting_device_is_a_reset_error() -> None:
    with SerialPhotometer(20_000.0, reset_on_open=True, boot_s=0.05) as dev:
        error, _ = failing(SerialDetector(config_for(dev)).open)
        assert error.kind == "reset"


def test_settle_without_a_banner_pattern_waits_settle_s(device: SerialPhotometer) -> None:
    det = SerialDetector(config_for(device, reset_banner=None, settle_s=0.1))
    _, elapsed = timed(det.open)
    det.close()
    assert waited_out(elapsed, 0.1)


def test_spy_url_logs_the_traffic(
    device: SerialPhotometer, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = default_config(f"spy://{device.path}", timeout_s=TIMEOUT_S)  # ?raw is broken
    with SerialDetector(cfg) as det:
        assert det.measure(EXPOSURE_S).value == 200.0
    err = capsys.readouterr().err
    assert "MEAS" in err
    assert "TX" in err and "RX" in err


def test_loop_url_skips_the_echo_of_its_own_command() -> None:
    # loop:// returns every byte written: the driver hears only its own query, skips it
    # as an echo, and times out instead of calling the echo malformed.
    cfg = SerialDetectorConfig(port="loop://", query="MEAS", timeout_s=0.1, retries=0)
    with SerialDetector(cfg) as det:
        error, elapsed = failing(lambda: det.measure(EXPOSURE_S))
    assert error.kind == "timeout"
    assert waited_out(elapsed, EXPOSURE_S + 0.1)


# -- validation ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("exposure_s", "averages"),
    [
        (0.0, 1),
        (-0.1, 1),
        (math.nan, 1),
        (math.inf, 1),
        ("0.1", 1),
        (True, 1),
        (None, 1),
        (0.1, 0),
        (0.1, -2),
        (0.1, 1.5),
        (0.1, True),
        (0.1, "2"),
        (0.0004, 1),  # rounds to 0 ms for "EXP {exposure_ms:d}"
    ],
)
def test_argument_validation_sends_nothing(
    device: SerialPhotometer, detector: SerialDetector, exposure_s: Any, averages: Any
) -> None:
    device.clear_commands()
    with pytest.raises(SerialDetectorValueError) as info:
        detector.measure(exposure_s, averages)
    assert isinstance(info.value, ValueError) and isinstance(info.value, DetectorError)
    assert info.value.kind == "invalid"
    assert detector.port in str(info.value)
    assert device.commands == []


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"port": ""}, "port"),
        ({"baud": 0}, "baud"),
        ({"response": r"VAL (\S+)"}, "(?P<value>"),
        ({"response": r"VAL (?P<value>\S+"}, "not a valid regular expression"),
        ({"query": "MEAS {exposure}"}, "allowed fields"),
        ({"query": "MEAS {exposure_s:d}"}, "cannot be formatted"),
        ({"query": "MEAS {"}, "not a valid template"),
        ({"set_exposure": "EXP {averages}"}, "allowed fields"),
        ({"init": "GAIN 1"}, "not one string"),
        ({"init": ("GAIN 1\nEXP 5",)}, "line ending"),
        ({"init": ("GAIN {exposure_ms}",)}, "allowed fields"),
        ({"line_ending": "\n\r"}, "line_ending"),
        ({"timeout_s": 0}, "timeout_s"),
        ({"timeout_s": math.inf}, "timeout_s"),
        ({"settle_s": -1}, "settle_s"),
        ({"retries": -1}, "retries"),
        ({"retries": 1.0}, "retries"),
        ({"full_scale": 0}, "full_scale"),
        ({"max_line_bytes": 8}, "max_line_bytes"),
        ({"device_averaging": True}, "{averages}"),
        ({"response": r"(?P<value>\S+)"}, "saturated_status needs"),
        ({"reset_banner": "(READY"}, "reset_banner"),
        ({"query": "MESS µ"}, "ASCII"),
    ],
)
def test_config_validation(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(SerialDetectorValueError) as info:
        default_config(overrides.pop("port", "/dev/null"), **overrides)
    assert message in str(info.value)
    assert isinstance(info.value, ValueError)


def test_config_is_frozen_and_init_becomes_a_tuple() -> None:
    cfg = default_config("/dev/null", init=["GAIN 1", "EXP 5"])
    assert cfg.init == ("GAIN 1", "EXP 5")
    with pytest.raises(AttributeError):
        cfg.port = "x"  # type: ignore[misc]
