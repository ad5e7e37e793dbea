"""The simulated photometer's protocol (the command table is in the package docstring):
its fixed lines, the driver configuration that speaks it, and line helpers."""

from __future__ import annotations

from typing import Any

from drivers.serial_detector import SerialDetectorConfig

BANNER = "READY gonio-sim photometer 1.0"
IDENTITY = "gonio-sim photometer 1.0"
#: The regular expression for the answer to ``MEAS`` (see :func:`default_config`).
RESPONSE = r"VAL (?P<value>\S+) (?P<status>OK|SAT)(?: (?P<std>\S+))?"
#: What the device sends instead of an answer under :meth:`SerialPhotometer.malformed`.
MALFORMED_LINE = "V#L 12?4 OK"


def default_config(port: str, **overrides: Any) -> SerialDetectorConfig:
    """The :class:`SerialDetectorConfig` matching this device's protocol.

    Host averaging with ``EXP`` sent on change; ``overrides`` replace any field. For
    device averaging pass ``query="MEAS {exposure_ms:d} {averages:d}"``,
    ``device_averaging=True`` and ``set_exposure=None``.
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


def _line(text: str) -> bytes:
    return (text + "\r\n").encode("ascii", "replace")


def _int_in(text: str, low: int, high: int) -> bool:
    return text.isdigit() and low <= int(text) <= high
