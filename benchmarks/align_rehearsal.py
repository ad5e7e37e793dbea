"""`gonio align`'s fly scan rehearsed on the hardware path at real speed: the arch rig
wired to hardware (configs/rigs/arch_serial.yaml), the real `DynamixelBus` polling the
byte-level emulator on its pty and the real `SerialDetector` streaming from the
simulated photometer on its pty, with a mirror misaligned by 0.2–0.8° in every
parameter (the glossy gold made a mirror, GGX α 0.005). Per run and speed-up: the peaks
found (of 18), the readings, the instrument time, the largest spread of one pose's
three peaks (the elevation in degrees; the azimuth in degrees of arc, × sin θo), and
the largest error of a determined parameter against the truth (zero offset of the
detector azimuth, the sample's tilt, the light's pointing across the plane), with the
load average at its start. The stop-and-go rehearsal (at --speedup 1000) is the
reference row (its instrument time is the rehearsal's clock, on which each serial
exchange's real time counts 1000 times).

Run: .venv/bin/python benchmarks/align_rehearsal.py [--runs 2] [--speedups 1 2]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
import numpy as np
import yaml
from _machine import describe

from drivers.errors import DriverError
from gonio.errors import GonioError
from gonio.rig import Rig, fit
from gonio.scene import load_scene
from gonio.workflows import align

ROOT = Path(__file__).resolve().parents[1]
RIG = ROOT / "configs" / "rigs" / "arch_serial.yaml"
GOLD = ROOT / "configs" / "scenes" / "glossy_metal.yaml"
TRUTH = {
    "zero_offset_deg": {
        "light_elevation": 0.7,
        "detector_azimuth": -0.4,
        "detector_elevation": 0.5,
        "sample_rotation": 0.3,
    },
    "tilt_deg": 0.5,
    "tilt_azimuth_deg": 40.0,
    "light_pointing_deg": [0.3, -0.2],
    "detector_pointing_deg": [-0.25, 0.3],
}


def errors(rig: Rig, peaks: np.ndarray) -> dict[str, float]:
    """Each checked parameter's error (°) against `TRUTH` (the tilt's azimuth as read,
    turned by the stage's zero offset)."""
    fitted = fit(rig, peaks, np.full(len(peaks), math.radians(align.PEAK_SIGMA_DEG)))
    d = {n: math.degrees(v) for n, v in zip(fitted.names, fitted.values, strict=True)}
    azimuth = math.radians(40.0 + 0.3)
    return {
        "zero_offset.detector_azimuth": d["zero_offset.detector_azimuth"] + 0.4,
        "tilt_x": d["tilt_x"] - 0.5 * math.cos(azimuth),
        "tilt_y": d["tilt_y"] - 0.5 * math.sin(azimuth),
        "light_pointing_x": d["light_pointing_x"] - 0.3,
    }


def spreads(rig: Rig, scan: align.Scan) -> tuple[float, float]:
    """The largest spread (°) of one pose's peaks: elevation, azimuth in arc."""
    settings = align.for_rig(rig, align.ScanSettings(), scan.mode)
    centers = align.nominal_poses(rig, settings)
    centers = centers[align.reachable(rig, centers, settings, scan.mode)]
    centers = centers[align.visiting_order(centers)]
    _, pose = np.unique(np.round(centers, 9), axis=0, return_inverse=True)
    el, az = rig.axes.index("detector_elevation"), rig.axes.index("detector_azimuth")
    worst_el = worst_az = 0.0
    for k in np.unique(pose):
        p = scan.peaks[np.ravel(pose) == k]
        worst_el = max(worst_el, float(np.degrees(np.ptp(p[:, el]))))
        arc = abs(math.sin(float(p[0, el])))
        worst_az = max(worst_az, float(np.degrees(np.ptp(p[:, az]))) * arc)
    return worst_el, worst_az


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--speedups", type=float, nargs="+", default=[1.0])
    args = parser.parse_args()
    print(describe())
    print(
        "\n| scan | speed-up | run | peaks | readings | instrument (min) | spread el (°) "
        "| spread az arc (°) | largest error (°) | load at start |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "rig.yaml").write_text(
            RIG.read_text(encoding="utf-8").replace("../", f"{RIG.parent.parent}/"), "utf-8"
        )
        rig = Rig.from_yaml(folder / "rig.yaml")
        data = yaml.safe_load(GOLD.read_text(encoding="utf-8"))
        data["material"]["alpha"] = 0.005
        data["effects"]["misalignment"] = TRUTH
        (folder / "mirror.yaml").write_text(yaml.safe_dump(data), encoding="utf-8")
        scene = load_scene(folder / "mirror.yaml", rig)
        runs = [(s, k) for s in args.speedups for k in range(args.runs)] + [(1000.0, 0)]
        for speedup, k in runs:
            load = os.getloadavg()[0]
            name = "fly" if align.fly_allowed("rehearsal", speedup) else "stop-and-go"
            try:
                scan = align.run_scan(
                    rig, scene, "rehearsal", align.ScanSettings(), speedup=speedup
                )
            except (GonioError, DriverError) as exc:  # a host starving the emulators
                print(f"| {name} | {speedup:g} | {k + 1} | failed: {exc} | | | | | | {load:.1f} |")
                continue
            el, az = spreads(rig, scan)
            worst = max(abs(e) for e in errors(rig, scan.peaks).values())
            span = max(scan.readings.ended_s) - min(scan.readings.started_s)
            print(
                f"| {name} | {speedup:g} | {k + 1} | {len(scan.peaks)} | "
                f"{len(scan.readings.value)} | {span / 60:.2f} | {el:.4f} | {az:.4f} | "
                f"{worst:.4f} | {load:.1f} |",
                flush=True,
            )
            time.sleep(1.0)


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="gonio align's fly scan rehearsed")
