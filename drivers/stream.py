"""The streaming part of the device contract (`drivers.base`): a detector that sends
readings unasked while the motors move.

Streaming (`StreamingDetector`, optional)
    ``start_stream(rate_hz, integration_s)`` starts readings of ``integration_s`` every
    ``1 / rate_hz`` s (``integration_s`` ≤ the period: windows never overlap);
    ``read_stream(timeout_s)`` returns the `StreamReading` values received since the
    last call (waiting at most ``timeout_s`` for a first one); ``stop_stream()`` stops,
    returns the last readings, leaves the instrument idle and usable for ``measure``,
    and is idempotent. Each reading's window (``started_s``, ``ended_s``) is on the
    host's clock, its stamps increase, windows do not overlap and ``ended_s −
    started_s`` is the integration. A stream that falls silent for longer than its
    backend's stall time is a `DetectorError`, never a hang. ``measure`` while
    streaming raises `DetectorError`. After a stream, `restamped` stamps its readings
    again with the stream's final clock offset when the device sent timestamps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Protocol

from drivers.base import Detector
from drivers.errors import StreamNotSupported


@dataclass(frozen=True)
class StreamReading:
    """One reading of a stream (`StreamingDetector`).

    ``value`` is the signal integrated over the window in the detector's units, ``std``
    the device's standard deviation of it when it sends one (else NaN: unknown),
    ``started_s`` / ``ended_s`` the integration window on the host's clock (s),
    ``saturated`` whether the window hit the full scale, ``device_t_s`` the device's
    own timestamp of the window's end (s on the device's clock) when it sends one, else
    None, ``received_s`` when the host received the reading (s on the host's clock;
    ``received_s − ended_s`` is the latency the stamps assume), and ``earliest_end_s`` the
    earliest the window can have ended on the host's clock when the driver knows a bound
    (a device whose first window begins when its start command arrives: not before the
    command left), else None. The window's true end lies between ``earliest_end_s`` and
    ``received_s``.
    """

    value: float
    std: float
    started_s: float
    ended_s: float
    saturated: bool = False
    device_t_s: float | None = None
    received_s: float | None = None
    earliest_end_s: float | None = None

    @property
    def middle_s(self) -> float:
        """The middle of the integration window (s): where the pose is interpolated."""
        return 0.5 * (self.started_s + self.ended_s)


def restamped(
    readings: Sequence[StreamReading], latency_s: float | None = 0.0
) -> list[StreamReading]:
    """``readings`` of one stream with their windows stamped again from the device's
    timestamps and the stream's final clock offset: ``ended_s = device_t_s + min(received_s
    − device_t_s) − latency_s`` (s), each window keeping its length; ``latency_s`` None:
    the smallest ``received_s − ended_s`` of the live stamps (the latency they assumed,
    the driver's configured one). A stream's live stamps use the offset known when each
    line arrived, which a host reading late overestimates at first (and later stamps,
    kept increasing, inherit); after the stream this removes that. Readings without a
    device timestamp (or an arrival time) are returned as they are."""
    timed = [r for r in readings if r.device_t_s is not None and r.received_s is not None]
    if not timed:
        return list(readings)
    if latency_s is None:
        latency_s = max(0.0, min(r.received_s - r.ended_s for r in timed))  # type: ignore[operator]
    offset = min(r.received_s - r.device_t_s for r in timed) - latency_s  # type: ignore[operator]
    out = []
    for r in readings:
        if r.device_t_s is None or r.received_s is None:
            out.append(r)
            continue
        ended = r.device_t_s + offset
        out.append(replace(r, started_s=ended - (r.ended_s - r.started_s), ended_s=ended))
    return out


class StreamingDetector(Detector, Protocol):
    """A detector with a streaming mode (rules: the module docstring)."""

    @property
    def can_stream(self) -> bool:
        """True: the streaming methods work (read through `can_stream`)."""
        ...

    def start_stream(self, rate_hz: float, integration_s: float | None = None) -> None:
        """Start readings of ``integration_s`` s (default: the whole period) every
        ``1 / rate_hz`` s. `DetectorError` for a rate or integration the detector cannot
        do (nothing is started), `StreamNotSupported` when it cannot stream."""
        ...

    def read_stream(self, timeout_s: float = 0.0) -> list[StreamReading]:
        """The readings received since the last call, in time order; with none yet,
        wait up to ``timeout_s`` (s) for the first. A stalled stream raises
        `DetectorError` (the stream is then stopped)."""
        ...

    def stop_stream(self) -> list[StreamReading]:
        """Stop (idempotent): the readings that arrived until the stream went quiet;
        the detector is idle and ``measure`` works again."""
        ...


def can_stream(detector: Detector) -> bool:
    """Whether ``detector`` offers a streaming mode (its optional ``can_stream``; False)."""
    return getattr(detector, "can_stream", False) is True


def streaming(detector: Detector) -> StreamingDetector:
    """``detector`` as a `StreamingDetector`; `StreamNotSupported` (one line naming it)
    when it cannot stream."""
    if not can_stream(detector):
        raise StreamNotSupported(
            f"{detector!r} cannot stream readings (no streaming mode, or none configured); "
            "use stop-and-go acquisition"
        )
    return detector  # type: ignore[return-value]
