"""`check_stream`: the stream check of a rig's serial detector, from the rig to its
`Verdict` (the probe's I/O, then the figures)."""

from __future__ import annotations

import datetime

from drivers.serial_detector.detector import SerialDetector
from gonio.config import ConfigError
from gonio.rig import Rig, SerialInterfaceSpec
from gonio.workflows.stream_check.figures import DEFAULT_LIMITS, Limits
from gonio.workflows.stream_check.judge import assess
from gonio.workflows.stream_check.probe import observe
from gonio.workflows.stream_check.verdict import Verdict, interface_config

#: The exposure (s) of the query sent after the streams, within the detector's range.
QUERY_EXPOSURE_S = 0.01


def check_stream(
    rig: Rig,
    *,
    port: str | None = None,
    rate_hz: float | None = None,
    duration_s: float = 2.0,
    starts: int = 5,
    identify: str | None = None,
    limits: Limits = DEFAULT_LIMITS,
) -> Verdict:
    """Check the streaming of ``rig``'s serial detector against the requirements of
    ``docs/reference/serial_detector.md``.

    Parameters
    ----------
    rig
        A rig whose ``detector.interface`` is ``serial`` with a ``stream`` section.
    port
        The port to use instead of the rig file's.
    rate_hz
        The rate to stream at (Hz); default the configuration's ``max_rate_hz``, which
        qualifies every plan's rate.
    duration_s
        How long the first stream lasts (s); the other ``starts − 1`` are short.
    starts
        How many streams are started (at least 2: the start is judged over them).
    identify
        A command whose one-line answer names the instrument (``ID?``, ``*IDN?``).
    limits
        What passes.

    Returns
    -------
    Verdict
        Every requirement's figures and pass/fail. `ConfigError` for a rig or an option
        that cannot be checked, `drivers.errors.DriverError` for a port that cannot be
        used: nothing was measured then.
    """
    where = rig.source or "rig"
    interface = rig.spec.detector.interface
    if not isinstance(interface, SerialInterfaceSpec):
        raise ConfigError(
            f"{where}: detector.interface: is {interface.kind!r}; expected a serial detector "
            "(kind: serial) with a stream section"
        )
    stream = interface.stream
    if stream is None:
        raise ConfigError(
            f"{where}: detector.interface.stream: none; expected a stream section (start, "
            "stop, line) to check"
        )
    if port is not None:
        interface = interface.model_copy(update={"port": port})
    top = stream.max_rate_hz
    rate = top if rate_hz is None else rate_hz
    if not 0 < rate <= top:
        raise ConfigError(
            f"--rate {rate:g}: expected a rate in (0, {top:g}] Hz (detector.interface.stream."
            "max_rate_hz)"
        )
    if not duration_s > 0 or starts < 2:
        raise ConfigError(f"expected --duration > 0 and --starts ≥ 2, got {duration_s}, {starts}")
    lo, hi = rig.spec.detector.exposure_range_s
    checked = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    config = interface.config()
    with SerialDetector(config, exposure_range_s=(lo, hi)) as detector:
        seen = observe(
            detector,
            rate_hz=rate,
            duration_s=duration_s,
            starts=starts,
            exposure_s=min(max(QUERY_EXPOSURE_S, lo), hi),
            identify=identify,
        )
    return Verdict(
        rig=str(where),
        checked_utc=checked,
        port=config.port,
        identity=seen.identity,
        config=interface_config(interface),
        rate_hz=rate,
        integration_s=seen.records[0].trace.integration_s,
        duration_s=duration_s,
        starts=starts,
        limits=limits,
        requirements=assess(seen.records, config, seen.query_error, limits),
    )
