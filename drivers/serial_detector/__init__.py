"""A detector on a line-based serial protocol: an Arduino/ADC photometer, a power meter.

The device answers text lines. For each sample the driver sends a query (a command
template such as ``"MEAS {exposure_ms:d}"``) and parses the answer with a regular
expression that has a named group ``value``. It is written to be left alone at night:

* it never hangs: every wait has a monotonic deadline (the exposure plus
  ``timeout_s``), writes have a timeout, and the port is closed without waiting for
  unsent bytes;
* every failure is a :class:`SerialDetectorError` (a :class:`~drivers.errors.DetectorError`)
  whose message is one line naming the port and what happened, with ``kind`` saying
  which failure it was (``"timeout"``, ``"malformed"``, ``"reset"``, ...);
* the port is always released: on leaving the context manager, when opening or
  initializing fails, and when the device goes away (unplugged) — the next call then
  opens it again;
* memory is bounded: a device spewing bytes without a line ending cannot grow a buffer
  beyond ``max_line_bytes``.

Line endings on input: ``\\r``, ``\\n`` and ``\\r\\n`` all end a line and blank lines
are ignored; ``line_ending`` is what the driver appends to the commands it sends. The
protocol, the configuration fields and the failure modes are described in
``docs/reference/serial_detector.md``.

The port may be a device path (``/dev/ttyACM0``, ``COM3``) or any pyserial URL:
``spy:///dev/ttyACM0?file=traffic.txt`` logs every byte, ``socket://host:port`` reaches a
network serial server. The driver is not thread-safe: use one instance from one thread.

The package exports the configuration and the errors without the serial stack (a rig
file is checked without opening anything); the driver is
`drivers.serial_detector.detector.SerialDetector`. The package:
:mod:`~drivers.serial_detector.errors` (the failures),
:mod:`~drivers.serial_detector.config` (the configuration and its validation),
:mod:`~drivers.serial_detector.arguments` (a measurement's and a stream's arguments),
:mod:`~drivers.serial_detector.lines` (the lines exchanged over the port, `LineIO`),
:mod:`~drivers.serial_detector.stream` (the streaming mode, `Streaming`),
:mod:`~drivers.serial_detector.trace` (what the driver saw of a stream) and
:mod:`~drivers.serial_detector.detector` (the driver, which holds a `LineIO` and a
`Streaming`). Its logger is ``drivers.serial_detector``.
"""

from drivers.serial_detector.config import EXPOSURE_FIELDS as EXPOSURE_FIELDS
from drivers.serial_detector.config import QUERY_FIELDS as QUERY_FIELDS
from drivers.serial_detector.config import STREAM_FIELDS as STREAM_FIELDS
from drivers.serial_detector.config import SerialDetectorConfig, SerialStreamConfig
from drivers.serial_detector.errors import (
    ErrorKind,
    SerialDetectorError,
    SerialDetectorValueError,
)
from drivers.serial_detector.trace import StreamTrace

__all__ = [
    "ErrorKind",
    "SerialDetectorConfig",
    "SerialDetectorError",
    "SerialDetectorValueError",
    "SerialStreamConfig",
    "StreamTrace",
]
