"""The serial detector's stream on the simulated photometer over a real pty: the rate
achieved, the latency of a line (its arrival on the host against the end of its window,
which the simulated device stamps on the host's own monotonic clock, so the truth is
known), and the error of the windows' end stamps the driver derives, with the device's
timestamps (live, and stamped again after the stream) and without them (the line count
as the device's clock, ``latency_s`` = 0), when the host reads the
stream as fast as it can (``read_stream(0.02)`` in a loop) and when it reads it every
20 ms (as an engine busy polling motors between reads might). The pty has no wire time:
a real line also spends its bytes × 10 / baud on the wire (printed for a 115 200 baud
line) and waits for the USB adapter's latency timer.
Run: .venv/bin/python benchmarks/stream.py [--seconds S]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from drivers.serial_detector.detector import SerialDetector
from drivers.stream import restamped
from sim.peers import STREAM_CONFIG, SerialPhotometer

RATES_HZ = (100.0, 500.0, 1000.0)
#: The data line without its timestamp: the host stamps arrivals only.
NO_DEVICE_TIME = r"DAT \S+ (?P<value>\S+) (?P<status>OK|SAT)"
EXAMPLE_LINE = "DAT 123456.789 1234.5 OK\r\n"


def run(rate_hz: float, seconds: float, *, device_time: bool, read_every_s: float) -> dict:
    stream = (
        STREAM_CONFIG if device_time else dataclasses.replace(STREAM_CONFIG, line=NO_DEVICE_TIME)
    )
    with SerialPhotometer(2e4) as dev:
        config = dev.config(stream=stream)
        with SerialDetector(config, exposure_range_s=(1e-3, 10.0)) as det:
            det.start_stream(rate_hz, 1e-3)
            readings = []
            t0 = time.monotonic()
            while time.monotonic() - t0 < seconds:
                if read_every_s:
                    time.sleep(read_every_s)
                    readings += det.read_stream()
                else:
                    readings += det.read_stream(0.02)
            duration = time.monotonic() - t0
            readings += det.stop_stream()
        truth = dev.stream_ends
    if len(truth) != len(readings):
        raise AssertionError(f"{len(truth)} lines sent, {len(readings)} readings")
    latency = [r.received_s - t for r, t in zip(readings, truth, strict=True)]
    error = [abs(r.ended_s - t) for r, t in zip(readings, truth, strict=True)]
    again = [abs(r.ended_s - t) for r, t in zip(restamped(readings), truth, strict=True)]
    return {"rate": len(readings) / duration, "latency": latency, "error": error, "again": again}


def ms(values: list[float], q: float) -> str:
    ordered = sorted(values)
    return f"{ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1e3:.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1.0)
    args = ap.parse_args()
    print(f"machine: {describe()}")
    wire = len(EXAMPLE_LINE) * 10 / 115_200
    print(
        f"a {len(EXAMPLE_LINE)}-byte line {EXAMPLE_LINE.strip()!r} on the wire at 115 200 baud: "
        f"{wire * 1e3:.2f} ms (at most {1 / wire:.0f} lines/s); {args.seconds:g} s per row, "
        "integration 1 ms\n"
    )
    print(
        "| rate asked (Hz) | host reads | achieved (Hz) | latency median (ms) | latency p95 "
        "(ms) | latency max (ms) | end stamp error with device time: median / max (ms) "
        "| the same, restamped after the stream (ms) | without device time: median / max "
        "(ms) |"
    )
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for rate in RATES_HZ:
        for every, label in ((0.0, "continuously"), (0.02, "every 20 ms")):
            a = run(rate, args.seconds, device_time=True, read_every_s=every)
            b = run(rate, args.seconds, device_time=False, read_every_s=every)
            print(
                f"| {rate:g} | {label} | {a['rate']:.1f} | {ms(a['latency'], 0.5)} | "
                f"{ms(a['latency'], 0.95)} | {ms(a['latency'], 1.0)} | "
                f"{ms(a['error'], 0.5)} / {ms(a['error'], 1.0)} | "
                f"{ms(a['again'], 0.5)} / {ms(a['again'], 1.0)} | "
                f"{ms(b['error'], 0.5)} / {ms(b['error'], 1.0)} |"
            )
    print(
        "\nLatency: the host's arrival stamp (`StreamReading.received_s`) less the true end "
        "of the line's window. End stamp error: |`ended_s` − the true end|. With the "
        "device's time the driver maps it to the host clock by the smallest arrival − "
        "device time seen so far (restamped: over the whole stream, `drivers.stream.restamped`); "
        "without it, the same with the line count × the period as the device's clock."
    )


if __name__ == "__main__":
    _report.run(
        main, __file__, __doc__, title="The serial detector's stream: rate and latency on a pty"
    )
