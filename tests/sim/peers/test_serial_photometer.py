"""The simulated photometer, spoken to line by line through its pseudo-terminal."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

from drivers.serial_detector import SerialDetectorConfig
from drivers.serial_detector.detector import SerialDetector
from sim.peers.serial_photometer import (
    BANNER,
    MALFORMED_LINE,
    RESPONSE,
    SerialPhotometer,
    default_config,
    main,
)

ROOT = Path(__file__).resolve().parents[3]


def took(elapsed: float, seconds: float) -> bool:
    """A modelled duration seen from the host on a shared machine: at least ``seconds``
    (the device's behaviour), at most ``seconds`` × 3 + 1 s (a guard against a hang or a
    slip of units; a busy machine only adds time, so no tighter bound holds)."""
    return seconds <= elapsed <= 3 * seconds + 1.0


class Host:
    """A plain pyserial host: send a line, read lines back (``\\r\\n`` included)."""

    def __init__(self, path: str) -> None:
        self.port = serial.Serial(path, 115200, timeout=0.5)

    def send(self, line: str, ending: str = "\n") -> None:
        self.port.write((line + ending).encode())

    def line(self, timeout: float = 0.5) -> bytes:
        self.port.timeout = timeout
        return bytes(self.port.read_until(b"\n"))

    def ask(self, line: str, timeout: float = 0.5) -> str:
        self.send(line)
        raw = self.line(timeout)
        assert raw.endswith(b"\r\n"), raw
        return raw.decode().rstrip("\r\n")

    def close(self) -> None:
        self.port.close()


@pytest.fixture
def photometer() -> Iterator[SerialPhotometer]:
    with SerialPhotometer(20_000.0) as dev:
        yield dev
    assert dev.error is None


@pytest.fixture
def host(photometer: SerialPhotometer) -> Iterator[Host]:
    h = Host(photometer.path)
    yield h
    h.close()


def test_commands_and_answers(photometer: SerialPhotometer, host: Host) -> None:
    assert host.ask("ID?") == "gonio-sim photometer 1.0"
    assert host.ask("MEAS") == "VAL 200.0 OK"  # 20 000 counts/s × the default 10 ms
    assert host.ask("EXP 50") == "OK"
    assert photometer.exposure_ms == 50
    assert host.ask("MEAS") == "VAL 1000.0 OK"
    assert host.ask("MEAS 5") == "VAL 100.0 OK"  # one-off exposure; the setting stays
    assert photometer.exposure_ms == 50
    assert host.ask("GAIN 2") == "OK"
    assert host.ask("MEAS 5") == "VAL 200.0 OK"
    assert host.ask("MEAS 5 3") == "VAL 200.0 OK 0.0"
    assert photometer.commands == [
        "ID?",
        "MEAS",
        "EXP 50",
        "MEAS",
        "MEAS 5",
        "GAIN 2",
        "MEAS 5",
        "MEAS 5 3",
    ]


@pytest.mark.parametrize(
    ("command", "answer"),
    [
        ("FOO", "ERR unknown command: FOO"),
        ("EXP", "ERR bad argument: EXP"),
        ("EXP 0", "ERR bad argument: EXP 0"),
        ("EXP x", "ERR bad argument: EXP x"),
        ("GAIN 65", "ERR bad argument: GAIN 65"),
        ("MEAS -5", "ERR bad argument: MEAS -5"),
        ("MEAS 5 0", "ERR bad averages: 0"),
        ("MEAS 1 2 3", "ERR bad argument: MEAS 1 2 3"),
    ],
)
def test_bad_commands(host: Host, command: str, answer: str) -> None:
    assert host.ask(command) == answer


@pytest.mark.parametrize("ending", ["\n", "\r", "\r\n"])
def test_any_line_ending_is_accepted(host: Host, ending: str) -> None:
    host.send("ID?", ending)
    assert host.line() == b"gonio-sim photometer 1.0\r\n"


def test_too_long_a_command_is_refused(host: Host) -> None:
    host.send("X" * 300)
    assert host.line() == b"ERR line too long\r\n"
    assert host.ask("ID?").startswith("gonio-sim")


def test_answers_take_the_exposure_time(host: Host) -> None:
    for command, seconds in (("MEAS 80", 0.08), ("MEAS 20 4", 0.08)):
        t0 = time.monotonic()
        host.ask(command)
        assert took(time.monotonic() - t0, seconds), command


def test_commands_are_processed_one_after_the_other(host: Host) -> None:
    t0 = time.monotonic()
    host.send("MEAS 50")
    host.send("ID?")  # queued behind the exposure, as on a single-threaded device
    assert host.line() == b"VAL 1000.0 OK\r\n"
    assert host.line() == b"gonio-sim photometer 1.0\r\n"
    assert time.monotonic() - t0 >= 0.05


def test_full_scale_clips_and_says_sat() -> None:
    with SerialPhotometer(1e6, full_scale=5000.0) as dev:
        h = Host(dev.path)
        try:
            assert h.ask("MEAS 1") == "VAL 1000.0 OK"
            assert h.ask("MEAS 10") == "VAL 5000.0 SAT"
            assert h.ask("MEAS 10 2") == "VAL 5000.0 SAT 0.0"
        finally:
            h.close()


def test_noise_is_seeded_and_gain_and_dark_apply() -> None:
    answers = []
    for _ in range(2):
        with SerialPhotometer(0.0, noise_std=5.0, dark=100.0, seed=7) as dev:
            h = Host(dev.path)
            try:
                h.ask("GAIN 2")
                answers.append([h.ask("MEAS 1") for _ in range(5)])
            finally:
                h.close()
    assert answers[0] == answers[1]
    values = [float(a.split()[1]) for a in answers[0]]
    assert len(set(values)) == 5
    assert all(150 < v < 250 for v in values)  # (0 + noise + 100) × 2


def test_a_callable_signal_gets_the_exposure() -> None:
    seen: list[float] = []

    def signal_(exposure_s: float) -> float:
        seen.append(exposure_s)
        return 42.0

    with SerialPhotometer(signal_) as dev:
        h = Host(dev.path)
        try:
            assert h.ask("MEAS 30") == "VAL 42.0 OK"
        finally:
            h.close()
    assert seen == [0.03]


def test_a_failing_signal_is_an_error_line_not_a_dead_thread() -> None:
    with SerialPhotometer(lambda _e: next(iter(()))) as dev:
        h = Host(dev.path)
        try:
            assert h.ask("MEAS") == "ERR signal failed: StopIteration"
            assert h.ask("ID?").startswith("gonio-sim")
        finally:
            h.close()
    assert dev.error is None


# -- faults -----------------------------------------------------------------------------


def test_malformed(photometer: SerialPhotometer, host: Host) -> None:
    photometer.malformed(2)
    assert host.ask("EXP 5") == "OK"  # only answers to MEAS are affected
    assert host.ask("MEAS") == MALFORMED_LINE
    assert host.ask("MEAS") == MALFORMED_LINE
    assert host.ask("MEAS") == "VAL 100.0 OK"
    assert re.fullmatch(RESPONSE, MALFORMED_LINE) is None


def test_inject(photometer: SerialPhotometer, host: Host) -> None:
    photometer.inject("VAL nan OK", "hello")
    assert host.ask("MEAS") == "VAL nan OK"
    assert host.ask("MEAS") == "hello"
    assert host.ask("MEAS") == "VAL 200.0 OK"


def test_silent_until_clear(photometer: SerialPhotometer, host: Host) -> None:
    photometer.silent()
    host.send("ID?")
    host.send("EXP 20")
    assert host.line(timeout=0.1) == b""
    assert photometer.exposure_ms == 10  # ignored, not just unanswered
    photometer.clear()
    assert host.ask("ID?").startswith("gonio-sim")
    assert photometer.commands == ["ID?", "EXP 20", "ID?"]


def test_reset_mid_read(photometer: SerialPhotometer, host: Host) -> None:
    """The banner comes half-way through a 300 ms exposure: after 150 ms and before the
    answer was due (a 150 ms margin for a busy machine); the answer never comes."""
    assert host.ask("EXP 300") == "OK"
    photometer.reset_mid_read()
    t0 = time.monotonic()
    host.send("MEAS")
    assert host.line() == (BANNER + "\r\n").encode()
    assert 0.15 <= time.monotonic() - t0 < 0.3
    assert host.line(timeout=0.25) == b""  # past the end of the exposure: no answer
    assert photometer.exposure_ms == 10
    assert photometer.resets == 1
    assert host.ask("MEAS") == "VAL 200.0 OK"


def test_reboot_now(photometer: SerialPhotometer, host: Host) -> None:
    host.ask("GAIN 3")
    photometer.reboot()
    assert host.line() == (BANNER + "\r\n").encode()
    assert photometer.gain == 1


def test_slow(photometer: SerialPhotometer, host: Host) -> None:
    """Slowed, an answer takes at least the delay; cleared, it comes sooner than the delay
    (a 0.3 s delay, so that a busy machine cannot make a prompt answer look slowed)."""
    photometer.slow(0.3)
    t0 = time.monotonic()
    assert host.ask("ID?", timeout=2.0).startswith("gonio-sim")
    assert time.monotonic() - t0 >= 0.3
    photometer.clear()
    t0 = time.monotonic()
    host.ask("ID?")
    assert time.monotonic() - t0 < 0.3


def test_garbage_without_newline(photometer: SerialPhotometer, host: Host) -> None:
    photometer.garbage_without_newline(25)
    host.send("MEAS")
    host.port.timeout = 0.2
    assert host.port.read(100) == b"0123456789012345678901234"
    assert host.ask("ID?") == "gonio-sim photometer 1.0"


def test_unsolicited(photometer: SerialPhotometer, host: Host) -> None:
    photometer.unsolicited("debug: hello")
    assert host.line() == b"debug: hello\r\n"


def test_echo() -> None:
    with SerialPhotometer(echo=True) as dev:
        h = Host(dev.path)
        try:
            h.send("ID?")
            assert h.line() == b"ID?\r\n"
            assert h.line() == b"gonio-sim photometer 1.0\r\n"
        finally:
            h.close()


def test_reset_on_open_prints_the_banner_after_boot() -> None:
    with SerialPhotometer(reset_on_open=True, boot_s=0.1) as dev:
        for _ in range(2):  # every open reboots it
            t0 = time.monotonic()
            h = Host(dev.path)
            try:
                assert h.line() == (BANNER + "\r\n").encode()
                assert took(time.monotonic() - t0, 0.1)
            finally:
                h.close()
        assert dev.resets == 2


# -- life cycle, configuration, command line ------------------------------------------------


def test_stop_closes_the_pty_and_is_idempotent() -> None:
    dev = SerialPhotometer()
    path = dev.start()
    assert dev.start() == path
    assert os.path.exists(path)
    dev.stop()
    dev.stop()
    assert not os.path.exists(path)
    with pytest.raises(RuntimeError, match="not started"):
        _ = SerialPhotometer().path


def test_default_config_matches_the_device(photometer: SerialPhotometer) -> None:
    cfg = default_config(photometer.path)
    assert isinstance(cfg, SerialDetectorConfig)
    assert photometer.config(timeout_s=0.3).timeout_s == 0.3
    match = re.fullmatch(cfg.response, "VAL 5.0 SAT 0.5")
    assert match is not None and match["status"] == "SAT" and match["std"] == "0.5"
    with SerialDetector(cfg) as det:
        assert det.measure(0.02).value == 400.0
    averaged = photometer.config(
        query="MEAS {exposure_ms:d} {averages:d}", device_averaging=True, set_exposure=None
    )
    with SerialDetector(averaged) as det:
        reading = det.measure(0.01, averages=3)
    assert (reading.value, reading.std, reading.n) == (200.0, 0.0, 3)


@pytest.mark.parametrize(
    "kwargs",
    [{"signal": float("nan")}, {"noise_std": -1.0}, {"full_scale": 0.0}, {"boot_s": -1.0}],
)
def test_constructor_validation(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError, match=r"must be"):
        SerialPhotometer(**kwargs)  # type: ignore[arg-type]


def test_main_serves_until_ctrl_c() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "sim.serial_photometer", "--signal", "1000"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        path = proc.stdout.readline().strip()
        assert path.startswith("/dev/")
        h = Host(path)
        try:
            assert h.ask("MEAS 100") == "VAL 100.0 OK"
        finally:
            h.close()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=5)
    finally:
        if proc.poll() is None:  # pragma: no cover - only if the test failed
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0
    assert "Traceback" not in err
    assert "Ctrl-C" in err


def test_main_rejects_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--signal", "lots"])
    assert info.value.code == 2
    assert "invalid float value" in capsys.readouterr().err
