"""The simulated photometer's protocol (the command table is in the package docstring):
its fixed lines, the driver configuration that speaks it, and line helpers."""

from __future__ import annotations

import re
from typing import Any

from drivers.serial_detector import SerialDetectorConfig, SerialStreamConfig

BANNER = "READY gonio-sim photometer 1.0"
IDENTITY = "gonio-sim photometer 1.0"
#: The regular expression for the answer to ``MEAS`` (see :func:`default_config`).
RESPONSE = r"VAL (?P<value>\S+) (?P<status>OK|SAT)(?: (?P<std>\S+))?"
#: The regular expression of a stream's data line (see :func:`default_config`).
STREAM_LINE = r"DAT (?P<device_t>\S+) (?P<value>\S+) (?P<status>OK|SAT)"
#: The streaming mode of this device's protocol (``default_config(path,
#: stream=STREAM_CONFIG)``): ``STREAM <hz> <ms>`` … ``STOP``, device times in ms.
STREAM_CONFIG = SerialStreamConfig(
    start="STREAM {rate_hz:g} {integration_ms:d}",
    stop="STOP",
    line=STREAM_LINE,
    rate_hz=100.0,
    max_rate_hz=2000.0,
    device_time_s=1e-3,
    starts_on_command=True,  # its first window begins when STREAM arrives
)
#: What the device sends instead of an answer under :meth:`SerialPhotometer.malformed`.
MALFORMED_LINE = "V#L 12?4 OK"


def default_config(port: str, **overrides: Any) -> SerialDetectorConfig:
    """The :class:`SerialDetectorConfig` matching this device's protocol.

    Host averaging with ``EXP`` sent on change; ``overrides`` replace any field. For
    device averaging pass ``query="MEAS {exposure_ms:d} {averages:d}"``,
    ``device_averaging=True`` and ``set_exposure=None``; for streaming
    ``stream=STREAM_CONFIG``.
    """
    fields: dict[str, Any] = {
        "port": port,
        "baud": 115200,
        "query": "MEAS",
        "set_exposure": "EXP {exposure_ms:d}",
        "response": RESPONSE,
        "line_ending": "\n",
        "timeout_s": 0.5,
        "retries": 2,
        "reset_banner": "^READY",
        "init": ("GAIN 1",),
        "command_ack": "^OK$",
        "error_reply": "^ERR",
        "saturated_status": "^SAT$",
    }
    fields.update(overrides)
    return SerialDetectorConfig(**fields)


#: The first word of every command the device knows.
COMMANDS = ("MEAS", "EXP", "GAIN", "ID?", "STREAM", "STOP")


def mismatch(config: SerialDetectorConfig) -> tuple[str, str] | None:
    """Why a driver configured with ``config`` cannot talk to this device, as (field,
    reason), or None when it can: each command it would send (rendered for 50 ms and 4
    averages) must be one of `COMMANDS`, and the device's answers must match
    ``response`` and ``command_ack``."""
    values = {"exposure_s": 0.05, "exposure_ms": 50, "exposure_us": 50_000, "averages": 4}
    commands = {"query": config.query.format(**values)}
    if config.set_exposure is not None:
        commands["set_exposure"] = config.set_exposure.format(**values)
    commands.update({f"init.{i}": command for i, command in enumerate(config.init)})
    if config.stream is not None:
        sample = {"rate_hz": 100.0, "period_ms": 10, "period_us": 10_000}
        sample |= {"integration_s": 0.008, "integration_ms": 8, "integration_us": 8_000}
        commands["stream.start"] = config.stream.start.format(**sample)
        commands["stream.stop"] = config.stream.stop
    for field, command in commands.items():
        word = (command.split() or [""])[0].upper()
        if word not in COMMANDS:
            known = ", ".join(COMMANDS)
            return field, f"{command!r} is not a command of the simulated photometer ({known})"
    answer = "VAL 1234.0 OK" + (" 5.0" if config.device_averaging else "")
    if re.fullmatch(config.response, answer) is None:
        return "response", f"does not match the simulated photometer's answer {answer!r}"
    if config.stream is not None and re.fullmatch(config.stream.line, "DAT 12.5 1234.0 OK") is None:
        return "stream.line", "does not match the simulated photometer's 'DAT 12.5 1234.0 OK'"
    if config.command_ack is not None and re.search(config.command_ack, "OK") is None:
        return "command_ack", "does not match the simulated photometer's acknowledgement 'OK'"
    return None


def _line(text: str) -> bytes:
    return (text + "\r\n").encode("ascii", "replace")


def _int_in(text: str, low: int, high: int) -> bool:
    return text.isdigit() and low <= int(text) <= high
