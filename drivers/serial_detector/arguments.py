"""The arguments of a serial detector's ``measure`` and ``start_stream``, checked before
anything is sent, and the values their command templates are filled with (pure: no
I/O)."""

from __future__ import annotations

import math
import string

from drivers.serial_detector.config import SerialStreamConfig, as_int, as_real
from drivers.serial_detector.errors import SerialDetectorValueError


def _invalid(port: str, what: str) -> SerialDetectorValueError:
    return SerialDetectorValueError(f"serial detector {port}: {what}", port=port, kind="invalid")


def measure_arguments(
    fields: frozenset[str],
    exposure_range_s: tuple[float, float],
    port: str,
    exposure_s: object,
    averages: object,
) -> tuple[float, int]:
    """``measure``'s exposure (s) and averages; `SerialDetectorValueError` (nothing
    sent) for an exposure not finite and positive, outside ``exposure_range_s`` or
    rounding to 0 in the templates' ``fields``, or averages not an integer ≥ 1."""
    exposure, n = as_real(exposure_s), as_int(averages)
    if exposure is None or not (0 < exposure < math.inf):
        raise _invalid(
            port, f"exposure_s must be a positive finite number of seconds, got {exposure_s!r}"
        )
    lo, hi = exposure_range_s
    if not lo <= exposure <= hi:
        raise _invalid(
            port, f"exposure {exposure!r} s is outside the detector's range [{lo:g}, {hi:g}] s"
        )
    if n is None or n < 1:
        raise _invalid(port, f"averages must be an integer ≥ 1, got {averages!r}")
    for name, scale, unit in (("exposure_ms", 1e3, "ms"), ("exposure_us", 1e6, "µs")):
        if name in fields and round(exposure * scale) < 1:
            raise _invalid(
                port,
                f"exposure_s={exposure!r} rounds to 0 {unit}, below the resolution "
                f"of the command templates",
            )
    return exposure, n


def integrated(fields: frozenset[str], exposure_s: float) -> float | None:
    """The exposure the device integrates when the templates round it (s), or None
    when it is the one asked."""
    for name, scale in (("exposure_ms", 1e3), ("exposure_us", 1e6)):
        if name in fields and "exposure_s" not in fields:
            integrated = round(exposure_s * scale) / scale
            return None if integrated == exposure_s else integrated
    return None


def template_values(exposure_s: float, averages: int) -> dict[str, float | int]:
    """The values of a query or set-exposure template's fields."""
    return {
        "exposure_s": exposure_s,
        "exposure_ms": round(exposure_s * 1e3),
        "exposure_us": round(exposure_s * 1e6),
        "averages": averages,
    }


def stream_arguments(
    cfg: SerialStreamConfig,
    exposure_range_s: tuple[float, float],
    port: str,
    rate_hz: float | None,
    integration_s: float | None,
) -> tuple[float, float, str]:
    """``start_stream``'s rate (Hz) and integration (s, as the start template rounds it)
    and the start command; `SerialDetectorValueError` (nothing sent) for a rate not in
    (0, ``max_rate_hz``], an integration not in (0, period], outside
    ``exposure_range_s`` or rounding to 0 in the template."""
    rate = as_real(cfg.rate_hz if rate_hz is None else rate_hz)
    if rate is None or not 0 < rate <= cfg.max_rate_hz:
        raise _invalid(
            port,
            f"stream rate_hz must be a number in (0, {cfg.max_rate_hz:g}] Hz "
            f"(stream.max_rate_hz), got {rate_hz!r}",
        )
    period = 1.0 / rate
    integration = as_real(period if integration_s is None else integration_s)
    if integration is None or not 0 < integration <= period * (1 + 1e-9):
        raise _invalid(
            port,
            f"stream integration_s must be in (0, {period:.6g}] s (the period at "
            f"{rate:g} Hz), got {integration_s!r}",
        )
    lo, hi = exposure_range_s
    if not lo <= integration <= hi:
        raise _invalid(
            port,
            f"stream integration {integration:.6g} s is outside the detector's range "
            f"[{lo:g}, {hi:g}] s",
        )
    fields = {
        "rate_hz": rate,
        "period_ms": round(period * 1e3),
        "period_us": round(period * 1e6),
        "integration_s": integration,
        "integration_ms": round(integration * 1e3),
        "integration_us": round(integration * 1e6),
    }
    names = {n for _, n, _, _ in string.Formatter().parse(cfg.start) if n is not None}
    # The integration the device does when the template rounds it.
    for name, scale in (("integration_ms", 1e3), ("integration_us", 1e6)):
        if name in names and "integration_s" not in names:
            units = round(integration * scale)
            if units / scale > period:  # never round past the period
                units = math.floor(period * scale)
            if units < 1:
                raise _invalid(
                    port, f"stream integration {integration!r} s rounds to 0 in {{{name}}}"
                )
            integration = units / scale
            fields[name] = units
            break
    return rate, min(integration, period), cfg.start.format(**fields)
