"""The verdict on each requirement of a streaming detector from what was observed of a
few streams (`gonio.workflows.stream_check.figures.StreamRecord`): pure arithmetic, no
I/O (the rates fitted by Theil–Sen, robust to a late line).

Times are on the host's clock (s). A window's end on that clock is placed from the
start command: the first window ends one period after the command left, the others
follow by the device's clock (its timestamps, or the line count × the period without
them). The fastest line of a stream bounds its latency from above: ``min(received −
device clock)`` is the clock offset plus the shortest latency.
"""

from __future__ import annotations

import math
import re

import numpy as np
from scipy.stats import theilslopes

from drivers.serial_detector import SerialDetectorConfig
from gonio.workflows.stream_check.figures import (
    DEFAULT_LIMITS,
    Figure,
    Limits,
    Requirement,
    StreamRecord,
)


def assess(
    records: list[StreamRecord],
    config: SerialDetectorConfig,
    query_error: str | None,
    limits: Limits = DEFAULT_LIMITS,
) -> list[Requirement]:
    """The verdict on every requirement of `REQUIREMENTS`, in its order, from the
    streams observed (the first the long one) and the error of the query sent after
    them (None: answered)."""
    if config.stream is None:
        raise ValueError("a stream check needs a configuration with a stream section")
    lines = [r for r in records if len(r.received_s)]
    results = [_stop(records, config, limits)]
    if not lines:
        why = "; ".join(e for r in records for e in (r.read_error, r.stop_error) if e)
        for name in ("starts_on_command", "steady_rate", "timestamps", "latency", "line_time"):
            results.append(Requirement(name, False, f"no data line received ({why or 'none'})"))
    else:
        unit = config.stream.device_time_s
        results += [
            _start(lines, config.stream.starts_on_command, unit, limits),
            _steady(records, unit, limits),
            _timestamps(lines, "device_t" in _groups(config.stream.line), limits),
            _latency(lines, limits),
            _line_time(lines, config.baud, limits),
        ]
    results.append(_idle(query_error))
    return results


def _groups(pattern: str) -> set[str]:
    return set(re.compile(pattern).groupindex)


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.2f} ms"


def _stop(records: list[StreamRecord], config: SerialDetectorConfig, limits: Limits) -> Requirement:
    name = "stop_acknowledged"
    if config.command_ack is None:
        return Requirement(
            name,
            False,
            "no command_ack in the configuration: the end of a stream cannot be told from "
            "a pause; set detector.interface.command_ack to the device's acknowledgement",
        )
    delays = [
        r.trace.stop_acknowledged_s - r.trace.stop_sent_s
        for r in records
        if r.trace.stop_acknowledged_s is not None and r.trace.stop_sent_s is not None
    ]
    after = sum(r.trace.lines_after_ack + r.data_after_stop for r in records)
    timeout = config.timeout_s
    worst = max(delays, default=math.nan)
    passed = len(delays) == len(records) and worst <= timeout and after == 0
    figures: dict[str, Figure] = {
        "stops": len(records),
        "acknowledged": len(delays),
        "ack_delay_median_s": float(np.median(delays)) if delays else None,
        "ack_delay_max_s": worst if delays else None,
        "timeout_s": timeout,
        "data_lines_after_ack": after,
    }
    summary = f"{len(delays)} of {len(records)} stops acknowledged"
    if delays:
        summary += f", at most {_ms(worst)} after STOP (limit timeout_s {_ms(timeout)})"
    summary += f"; {after} data line(s) after the acknowledgement"
    return Requirement(name, passed, summary, figures)


def _start(records: list[StreamRecord], claimed: bool, unit: float, limits: Limits) -> Requirement:
    leads = np.array([r.lead_s() for r in records])
    replies = np.array(
        [
            0.0
            if r.trace.start_acknowledged_s is None
            else r.trace.start_acknowledged_s - r.trace.sent_s
            for r in records
        ]
    )
    # Less the command's round trip, which latency (or a slow delivery) alone explains;
    # a first window begun before the command keeps its negative lead.
    late = leads - np.clip(replies, 0.0, np.maximum(leads, 0.0))
    tolerance = max(limits.start_tolerance * records[0].period_s, unit)
    early, spread = float(leads.min()), float(late.max() - late.min())
    problems = []
    if early < -tolerance:
        problems.append(f"begins {_ms(-early)} before the command (aligned to its own tick?)")
    if float(late.max()) > tolerance:
        problems.append(f"begins {_ms(float(late.max()))} after the command arrives")
    if spread > tolerance:
        problems.append(f"varies by {_ms(spread)} from start to start")
    figures: dict[str, Figure] = {
        "starts": len(records),
        "claimed": claimed,
        "lead_min_s": early,
        "lead_max_s": float(leads.max()),
        "start_reply_median_s": float(np.median(replies)),
        "late_max_s": float(late.max()),
        "tolerance_s": tolerance,
    }
    measured = (
        f"over {len(records)} starts the first window begins {_ms(float(late.min()))} to "
        f"{_ms(float(late.max()))} after the command arrives (a lead of {_ms(early)} to "
        f"{_ms(float(leads.max()))} less the command's round trip; tolerance {_ms(tolerance)})"
    )
    if not problems:
        note = "" if claimed else "; starts_on_command is false: it may be set true"
        return Requirement("starts_on_command", True, measured + note, figures)
    if not claimed:
        note = "; it does not, and starts_on_command is false: stamped from the arrivals"
        return Requirement("starts_on_command", True, measured + note, figures)
    return Requirement("starts_on_command", False, "; ".join(problems) + ": " + measured, figures)


def _steady(records: list[StreamRecord], unit: float, limits: Limits) -> Requirement:
    errors = [e for r in records for e in (r.read_error,) if e]
    lines = [r for r in records if len(r.received_s) > 1]
    period = records[0].period_s
    asked = records[0].trace.rate_hz
    spans = sum(float(r.received_s[-1] - r.received_s[0]) for r in lines)
    timed = all(r.timed and bool(np.all(np.diff(r.device_t_s) > 0)) for r in lines)
    achieved = _host_rate(lines, period, timed)
    intervals = np.concatenate([np.diff(r.clock() if timed else r.received_s) for r in lines])
    steps = np.maximum(np.rint(intervals / period), 1.0)
    if timed:
        lost = int(np.sum(steps - 1))
    else:  # the arrivals batch: count the lines a steady rate would have sent
        lost = max(0, round(spans / period) + len(lines) - sum(len(r.received_s) for r in lines))
    whole = intervals[steps == 1] if timed else intervals
    deviation = np.abs(whole - period) / period if len(whole) else np.zeros(1)
    p95 = float(np.percentile(deviation, 95))
    tolerance = max(limits.interval_tolerance, unit / period)
    rate_error = achieved / asked - 1
    problems = list(errors)
    if not abs(rate_error) <= limits.rate_tolerance:
        problems.append(f"{achieved:.4g} Hz achieved for {asked:g} Hz asked ({rate_error:+.2%})")
    if lost:
        problems.append(f"{lost} line(s) lost")
    if timed and p95 > tolerance:
        problems.append(f"intervals off the period by {p95:.0%} (95th percentile)")
    figures: dict[str, Figure] = {
        "asked_hz": asked,
        "achieved_hz": achieved,
        "rate_error": rate_error,
        "lines": sum(len(r.received_s) for r in records),
        "lost_lines": lost,
        "interval_p95_deviation": p95,
        "interval_max_deviation": float(deviation.max()),
        "intervals_from": "device clock" if timed else "arrivals",
    }
    measured = (
        f"{achieved:.5g} Hz for {asked:g} Hz asked ({rate_error:+.3%}), {lost} lost of "
        f"{figures['lines']}, intervals within {p95:.1%} of the period (95th percentile, "
        f"{'device clock' if timed else 'arrivals'}; tolerance {tolerance:.0%})"
    )
    if problems:
        return Requirement("steady_rate", False, "; ".join(problems) + ": " + measured, figures)
    return Requirement("steady_rate", True, measured, figures)


def _host_rate(lines: list[StreamRecord], period: float, timed: bool) -> float:
    """The lines' rate on the host's clock (Hz): the median over the streams of the
    Theil–Sen slope (Sen 1968) of each line's arrival against its window's slot (its
    device-clock step from the first, or its count without timestamps), so that a few
    lines a busy host read late do not move it as they move a first-to-last span."""
    rates = []
    for r in lines:
        slots = (
            np.concatenate(
                [[0.0], np.cumsum(np.maximum(np.rint(np.diff(r.device_t_s) / period), 1))]
            )
            if timed
            else np.arange(len(r.received_s), dtype=np.float64)
        )
        slope = float(theilslopes(r.received_s, slots)[0])
        if slope > 0:
            rates.append(1.0 / slope)
    return float(np.median(rates)) if rates else math.nan


def _timestamps(records: list[StreamRecord], has_group: bool, limits: Limits) -> Requirement:
    name = "timestamps"
    if not has_group:
        return Requirement(
            name,
            True,
            "none: the stream line has no device_t group (recommended: the windows are "
            "then stamped from their arrival)",
            {"present": 0},
        )
    n = sum(len(r.device_t_s) for r in records)
    present = sum(int(np.count_nonzero(np.isfinite(r.device_t_s))) for r in records)
    steps = [np.diff(r.device_t_s[np.isfinite(r.device_t_s)]) for r in records]
    backward = sum(int(np.count_nonzero(d <= 0)) for d in steps)
    rates, ratios = [], []
    for r in records:
        t, h = r.device_t_s, r.received_s
        ok = np.isfinite(t)
        if np.count_nonzero(ok) > 1 and t[ok][-1] > t[ok][0]:
            rates.append(1.0 / float(np.median(np.diff(t[ok]))))  # lost lines aside
            # device seconds per host second, robust to lines a busy host read late
            ratios.append(float(theilslopes(t[ok], h[ok])[0]))
    asked = records[0].trace.rate_hz
    rate = float(np.median(rates)) if rates else math.nan
    ratio = float(np.median(ratios)) if ratios else math.nan
    problems = []
    if present < n:
        problems.append(f"missing on {n - present} of {n} lines")
    if backward:
        problems.append(f"{backward} step(s) back or standing still")
    if not abs(rate / asked - 1) <= limits.rate_tolerance:
        problems.append(f"{rate:.4g} Hz by the device's clock for {asked:g} Hz asked")
    if not abs(ratio - 1) <= limits.rate_tolerance:
        problems.append(f"the device's clock runs {ratio:.4g}× the host's (device_time_s?)")
    figures: dict[str, Figure] = {
        "lines": n,
        "present": present,
        "backward_steps": backward,
        "device_rate_hz": rate,
        "device_to_host_clock": ratio,
    }
    measured = (
        f"on {present} of {n} lines, {backward} step(s) back, {rate:.5g} Hz by the device's "
        f"clock, which runs {ratio:.5f}× the host's"
    )
    if problems:
        return Requirement(name, False, "; ".join(problems) + ": " + measured, figures)
    return Requirement(name, True, measured, figures)


def _latency(records: list[StreamRecord], limits: Limits) -> Requirement:
    latency = np.concatenate([r.latencies_s() for r in records])
    median = float(np.median(latency))
    p95 = float(np.percentile(latency, 95))
    low = float(latency.min())
    figures: dict[str, Figure] = {
        "median_s": median,
        "p95_s": p95,
        "min_s": low,
        "max_s": float(latency.max()),
        "spread_s": p95 - low,
    }
    measured = (
        f"arrival − window end: median {_ms(median)}, 95th percentile {_ms(p95)}, spread "
        f"{_ms(p95 - low)} (limits {_ms(limits.latency_median_s)}, {_ms(limits.latency_p95_s)})"
    )
    passed = median <= limits.latency_median_s and p95 <= limits.latency_p95_s
    return Requirement("latency", passed, measured if passed else "too late: " + measured, figures)


def _line_time(records: list[StreamRecord], baud: int, limits: Limits) -> Requirement:
    longest = max(r.trace.longest_line_bytes for r in records) + 2
    wire = longest * 10 / baud
    share = wire / records[0].period_s
    figures: dict[str, Figure] = {
        "longest_line_bytes": longest,
        "wire_s": wire,
        "share_of_period": share,
    }
    measured = (
        f"{longest} bytes take {_ms(wire)} at {baud} baud, {share:.0%} of the period "
        f"(limit {limits.line_share:.0%})"
    )
    passed = share <= limits.line_share
    return Requirement(
        "line_time", passed, measured if passed else "too long: " + measured, figures
    )


def _idle(query_error: str | None) -> Requirement:
    if query_error is None:
        return Requirement("idle_after_stop", True, "answered a query after its streams")
    return Requirement("idle_after_stop", False, f"no answer to a query after STOP: {query_error}")
