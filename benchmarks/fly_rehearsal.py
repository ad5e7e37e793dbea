"""Fly plans rehearsed: the share of their targets a rehearsal keeps at --speedup 5.

`gonio acquire PLAN --rehearse --speedup 5` of configs/plans/fly_rehearsal.yaml (detector
arcs) and of the same plan as lines along θh (`fly.segment: theta_h_line`, 1° blur
budget, every axis following a trajectory) on the arch rig wired to hardware
(configs/rigs/arch_serial.yaml): the real `DynamixelBus` on the Dynamixel emulator, the
real `SerialDetector` on the simulated photometer streaming 100 readings a second, each
on its own pty, the rehearsal's clock five times real time, on the glossy gold scene.
Each plan is rehearsed --runs times in a child process beside --busy processes spinning
on the CPU (each in a session of its own, as other jobs on a shared host would be;
started --warmup seconds ahead, so that the load average has climbed); per run: the
targets kept (of the plan's), the sweeps redone (kept fewer readings than asked: a host
stall), the wall time, and the 1-minute load average at its end. The figure that
matters is the share kept on a loaded machine.
Run: .venv/bin/python benchmarks/fly_rehearsal.py [--runs 3] [--busy 4] [--warmup 60]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import FrameType

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _busy import spinning
from _machine import describe

from gonio.store import open_run

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "configs" / "plans" / "fly_rehearsal.yaml"
SCENE = ROOT / "configs" / "scenes" / "glossy_metal_fly.yaml"
SPEEDUP = 5
GONIO = Path(sys.executable).with_name("gonio")


def lines_plan(folder: Path) -> Path:
    """The rehearsal plan as lines along θh (1° blur budget)."""
    out = folder / "fly_rehearsal_lines.yaml"
    out.write_text(
        PLAN.read_text()
        .replace("rig: ../rigs/", f"rig: {PLAN.parent.parent / 'rigs'}/")
        .replace("blur_deg: 0.5", "blur_deg: 1.0\n    segment: theta_h_line")
    )
    return out


def rehearse(plan: Path, out: Path, failures: list[str]) -> dict[str, float]:
    """One rehearsal of ``plan`` into ``out``: its figures (a failed one's reason added
    to ``failures``)."""
    started = time.perf_counter()
    result = subprocess.run(
        [str(GONIO), "acquire", str(plan), "--scene", str(SCENE), "--rehearse", "--speedup",
         str(SPEEDUP), "-o", str(out), "--overwrite", "-q"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    wall = time.perf_counter() - started
    load = os.getloadavg()[0]
    if result.returncode != 0:  # counted as none kept, its reason printed below the table
        failures.append(f"{plan.name}: {result.stderr.strip()}")
        return {"kept": 0, "targets": 1, "sweeps": 0, "redone": 0, "wall": wall, "load": load}
    run = open_run(out)
    redone = sum(1 for s in run.sweeps if s.outcome == "abandoned" and s.data.get("short"))
    return {
        "kept": len(run), "targets": len(run.plan), "sweeps": len(run.plan.sweeps or ()),
        "redone": redone, "wall": wall, "load": load,
    }  # fmt: skip


def stop(signum: int, frame: FrameType | None) -> None:
    raise SystemExit(128 + signum)  # the spinning processes are ended on the way out


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="rehearsals of each plan (3)")
    parser.add_argument("--busy", type=int, default=4, help="spinning processes beside (4)")
    parser.add_argument("--warmup", type=float, default=60.0, help="s of spinning ahead (60)")
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, stop)
    print(describe())
    print(
        f"\n{args.busy} processes spinning beside on {os.cpu_count()} cores, started "
        f"{args.warmup:.0f} s ahead."
    )
    print(
        "\n| plan | run | targets kept | of | share | sweeps | redone short | wall (s) "
        "| load at end |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp, spinning(args.busy):
        time.sleep(args.warmup if args.busy else 0.0)
        folder = Path(tmp)
        plans = {"detector arcs, 0.5°": PLAN, "θh lines, 1°": lines_plan(folder)}
        failures: list[str] = []
        for name, plan in plans.items():
            shares, loads = [], []
            for k in range(args.runs):
                f = rehearse(plan, folder / f"run{k}.sqlite", failures)
                share = f["kept"] / f["targets"]
                shares.append(share)
                loads.append(f["load"])
                print(
                    f"| {name} | {k + 1} | {f['kept']:.0f} | {f['targets']:.0f} | "
                    f"{100 * share:.1f} % | {f['sweeps']:.0f} | {f['redone']:.0f} | "
                    f"{f['wall']:.1f} | {f['load']:.2f} |",
                    flush=True,
                )
            print(
                f"| {name} | least | | | {100 * min(shares):.1f} % | | | | "
                f"{min(loads):.2f}–{max(loads):.2f} |"
            )
    for failure in failures:
        print(f"\nA rehearsal failed (none kept): {failure}")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Fly plans rehearsed")
