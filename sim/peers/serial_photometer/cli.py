"""The command line: ``python -m sim.serial_photometer`` serves a simulated photometer."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from sim.peers.serial_photometer.device import SerialPhotometer


def main(argv: Sequence[str] | None = None) -> int:
    """Serve a simulated photometer until Ctrl-C; print the pty path first."""
    parser = argparse.ArgumentParser(
        prog="python -m sim.serial_photometer",
        description="Serve a simulated line-based photometer on a pseudo-terminal.",
    )
    parser.add_argument("--signal", type=float, default=20_000.0, help="counts per second")
    parser.add_argument("--noise", type=float, default=0.0, help="noise std in counts")
    parser.add_argument("--full-scale", type=float, default=65535.0, help="saturation counts")
    parser.add_argument("--reply-delay", type=float, default=0.0, help="extra seconds per answer")
    parser.add_argument(
        "--reset-on-open", action="store_true", help="reboot when a host opens the port"
    )
    parser.add_argument("--boot", type=float, default=0.0, help="seconds from reset to banner")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    device = SerialPhotometer(
        args.signal,
        noise_std=args.noise,
        full_scale=args.full_scale,
        reply_delay_s=args.reply_delay,
        reset_on_open=args.reset_on_open,
        boot_s=args.boot,
        seed=args.seed,
    )
    try:
        with device:
            print(device.path, flush=True)
            print(
                f"serving a simulated photometer on {device.path} (protocol: see "
                "docs/reference/serial_detector.md); Ctrl-C to stop",
                file=sys.stderr,
                flush=True,
            )
            while True:
                time.sleep(3600)
    except KeyboardInterrupt:
        pass
    return 0
