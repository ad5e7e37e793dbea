"""A simulated line-based photometer served on a pseudo-terminal.

It speaks the protocol of ``docs/reference/serial_detector.md`` (the Arduino example) so that
:class:`drivers.serial_detector.detector.SerialDetector` can be exercised, byte for byte, on a
real tty without hardware, and faults can be injected (malformed lines, silence, a reset
in the middle of a reading, slow answers, bytes without a line ending).

Protocol (commands end with ``\\n``, ``\\r`` or ``\\r\\n``; answers end with ``\\r\\n``
like an Arduino's ``println``):

==================  ============================================================
``EXP <ms>``        set the integration time (1 … 60000 ms) → ``OK``
``GAIN <g>``        set the gain (1 … 64) → ``OK``
``MEAS``            one exposure at the set time → ``VAL <counts> <OK|SAT>``
``MEAS <ms>``       one exposure of ``<ms>`` → ``VAL <counts> <OK|SAT>``
``MEAS <ms> <n>``   the mean of ``n`` exposures → ``VAL <mean> <OK|SAT> <std>``
``ID?``             → ``gonio-sim photometer 1.0``
``STREAM <hz> <ms>``  stream: ``OK``, then every 1/hz s a line
                    ``DAT <t_ms> <counts> <OK|SAT>`` (an integration of ``<ms>``
                    ending at ``t_ms``, the device's clock in ms since it started)
``STOP``            stop streaming → ``OK`` (also when idle)
anything else       → ``ERR <reason>`` (while streaming: ``ERR streaming: ...``)
==================  ============================================================

A stream's counts come from ``signal`` like a ``MEAS``'s, evaluated at the middle of
each window: a callable signal reads the simulation's pose and time of that moment (a
rehearsal's reads the emulated motors' true positions).

After a reset the device prints ``READY gonio-sim photometer 1.0`` and forgets its
exposure and gain. Commands are processed one after the other, each taking its
exposure time (plus ``reply_delay_s``), as on a real single-threaded device.

``python -m sim.serial_photometer`` prints the pty path and serves until Ctrl-C.

The package: :mod:`~sim.peers.serial_photometer.protocol` (the device's fixed lines and the
matching driver configuration), :mod:`~sim.peers.serial_photometer.device` (the photometer:
its settings, answers and stream; the pty and the serving thread are its
`sim.peers.line_server.LineServer`'s), :mod:`~sim.peers.serial_photometer.sensor` (what
an exposure reads), :mod:`~sim.peers.serial_photometer.faults` (the faults a test
injects), :mod:`~sim.peers.serial_photometer.quirks` (the
ways its stream can fall short of the requirements, for testing a qualification) and
:mod:`~sim.peers.serial_photometer.cli` (the command line).
"""

from sim.peers.serial_photometer.cli import main
from sim.peers.serial_photometer.device import SerialPhotometer
from sim.peers.serial_photometer.protocol import (
    BANNER,
    MALFORMED_LINE,
    RESPONSE,
    STREAM_CONFIG,
    default_config,
)
from sim.peers.serial_photometer.protocol import IDENTITY as IDENTITY
from sim.peers.serial_photometer.quirks import StreamQuirks
from sim.peers.serial_photometer.sensor import Signal as Signal

__all__ = [
    "BANNER",
    "MALFORMED_LINE",
    "RESPONSE",
    "STREAM_CONFIG",
    "SerialPhotometer",
    "StreamQuirks",
    "default_config",
    "main",
]
