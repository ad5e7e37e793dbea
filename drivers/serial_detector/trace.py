"""What the driver saw of one stream's conversation (`StreamTrace`): when the start and
stop commands left and were acknowledged, and what arrived after the stop's
acknowledgement. A qualification of the instrument reads it (``SerialDetector.last_stream``);
acquisition does not need it."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class StreamTrace:
    """One stream as the driver saw it; every time is on the detector's clock (s).

    ``command`` is the start command sent for ``rate_hz`` (Hz) and ``integration_s`` (s,
    as the template rounds it); ``sent_s`` the clock just before it left and
    ``start_acknowledged_s`` when its acknowledgement was read (None: no ``command_ack``,
    or none came before the first data line). ``stop_sent_s`` is the clock just before
    ``stop`` left (None: the stream failed before it was stopped) and
    ``stop_acknowledged_s`` when its acknowledgement was read (None: none within the
    driver's wait). ``data_lines`` counts the data lines read, ``lines_after_ack`` those
    read after the stop's acknowledgement (a conforming device sends none), and
    ``longest_line_bytes`` the longest data line (without its line ending).
    """

    command: str
    rate_hz: float
    integration_s: float
    sent_s: float
    start_acknowledged_s: float | None
    stop_sent_s: float | None
    stop_acknowledged_s: float | None
    data_lines: int
    lines_after_ack: int
    longest_line_bytes: int
