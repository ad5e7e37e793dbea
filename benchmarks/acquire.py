"""Acquisition engine costs.

1. Engine + journal overhead per sample on the simulated backend: `gonio acquire`'s
   loop (limits, measure, saturation check, journal row with FK of the read-back
   angles and the simulator's snapshot, one committed SQLite transaction per sample)
   against the bare simulated devices measuring the same targets one by one
   (`SimulatedInstrument.run`, the same `measure_target` step, no journal), both with
   the detector's optics precomputed. Targets: overhead ≤ 200 µs per sample, and
   ≥ 2 000 samples/s with the demo's effects (the glossy-metal scene).
2. The durable commit (hardware path: `synchronous=FULL`, one fsync'ed WAL commit per
   sample) against the plain one (simulated backend), per sample, timed in a folder of
   runs/ (where the tutorials' `gonio acquire -o runs/…` writes, on the disk this page
   is written to), median and 90th percentile of every commit; a bare fsync of 4 KiB
   appended to a file there; and the durable commit as a share of the shortest target
   of the shipped stop-and-go plans (move + settle + exposure + the bus's time, as
   `gonio plan` predicts it; a fly plan commits a sweep's readings at once; target
   ≤ 2 %). The durable figure is the disk's, not gonio's: each commit waits for the
   WAL's fsync (`synchronous=FULL`; `NORMAL` fsyncs only at checkpoints), which waits
   for the filesystem's journal commit (ext4 commits it on fsync) and for the device to
   flush its write cache (a virtual disk: the host's storage behind it), behind
   whatever other writers left dirty in the page cache, so it grows with the machine's
   load. The page names the filesystem, the device and the load it was measured with;
   on another disk measure it again.

Run: .venv/bin/python benchmarks/acquire.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import _report
import numpy as np
from _machine import describe

from gonio.planner import Plan, load_plan_source
from gonio.scene import Scene
from gonio.store import Journal, samples_table
from gonio.workflows import session
from sim.virtual import SimulatedInstrument
from tests.support.measure import measure_targets

ROOT = Path(__file__).resolve().parents[1]
PLANS = {
    "quickstart": ROOT / "configs/plans/quickstart.yaml",
    "isotropic": ROOT / "configs/plans/isotropic_hybrid.yaml",
}
SCENES = {
    "matte": ROOT / "configs/scenes/matte.yaml",
    "glossy": ROOT / "configs/scenes/glossy_metal.yaml",
}
#: Where the tutorials write their runs (ignored by git): the commits are timed there.
RUNS = ROOT / "runs"
#: Bytes one bare fsync follows (a page).
PAGE_BYTES = 4096


def bare(plan: Plan, scene: Scene) -> float:
    """Wall seconds of the bare devices measuring every target (optics precomputed)."""
    with SimulatedInstrument(scene, plan.rig) as inst:
        t = time.perf_counter()
        measure_targets(inst, plan)
        return time.perf_counter() - t


def engine(source: session.Files, plan: Plan, scene: Scene, folder: Path) -> float:
    """Wall seconds of the engine's loop over every target (calibrations excluded: the
    time between the first and the last sample's commit, scaled to every sample)."""
    out = folder / "bench.sqlite"
    stamps: list[float] = []

    class Clock:
        def start(self, plan: Plan, todo: np.ndarray) -> None:
            stamps.append(time.perf_counter())

        def advance(self, done: int) -> None:
            stamps.append(time.perf_counter())

        def close(self) -> None:
            pass

    session.start(plan, source, scene=scene, output=out, overwrite=True, progress=Clock())
    return (stamps[-1] - stamps[0]) * len(plan) / max(len(stamps) - 1, 1)


def commit_costs(folder: Path, durable: bool, n: int = 300) -> np.ndarray:
    """Seconds of each of ``n`` committed sample rows."""
    axes, coords = ["a", "b", "c", "d"], ["x", "y", "z"]
    meta = {"axes": axes, "coordinate_names": coords}
    path = folder / f"commit-{durable}.sqlite"
    path.unlink(missing_ok=True)
    row = dict.fromkeys((c.name for c in samples_table(axes, coords)), 0.5)
    row.update(utc="2026-01-01T00:00:00", temperatures_c=None, sim_state=None)
    out = np.empty(n)
    with Journal.create(path, meta, b"", durable=durable, overwrite=True) as journal:
        journal.start_session("t", {})
        for i in range(n):
            t = time.perf_counter()
            journal.sample({**row, "target": i})
            out[i] = time.perf_counter() - t
    return out


def fsync_costs(folder: Path, n: int = 300) -> np.ndarray:
    """Seconds of each of ``n`` fsyncs, each after appending `PAGE_BYTES` to one file."""
    out = np.empty(n)
    fd = os.open(folder / "fsync.bin", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    try:
        for i in range(n):
            os.write(fd, bytes(PAGE_BYTES))
            t = time.perf_counter()
            os.fsync(fd)
            out[i] = time.perf_counter() - t
    finally:
        os.close(fd)
    return out


def storage(folder: Path) -> str:
    """The filesystem ``folder`` is on (type, device, mount options; Linux's mountinfo)
    and what the kernel says of the device: its write cache and whether it rotates."""
    path = folder.resolve()
    best: tuple[int, str] = (-1, "unknown filesystem")
    try:
        lines = Path("/proc/self/mountinfo").read_text().splitlines()
    except OSError:
        return best[1]
    for line in lines:
        head, _, tail = line.partition(" - ")
        fields, rest = head.split(), tail.split()
        mount = Path(fields[4])
        if len(rest) >= 3 and path.is_relative_to(mount) and len(mount.parts) > best[0]:
            kind, device, options = rest[0], rest[1], fields[5]
            best = (len(mount.parts), f"{kind} on {device} mounted {options}{_device(device)}")
    return best[1]


def _device(device: str) -> str:
    """``; the device: write back cache, …`` for a block device (its partition's disk),
    or nothing when sysfs does not say."""
    block = Path("/sys/class/block") / Path(device).name
    queue = block / "queue" if (block / "queue").is_dir() else block.resolve().parent / "queue"
    try:
        cache = (queue / "write_cache").read_text().strip()
        rotating = (queue / "rotational").read_text().strip() == "1"
    except OSError:
        return ""
    return f"; the device: {cache} cache, {'' if rotating else 'not '}rotational to the kernel"


def shortest_target_s() -> tuple[str, float]:
    """(plan, s) of the shortest target of the shipped stop-and-go plans, as predicted."""
    best = ("", np.inf)
    for path in sorted((ROOT / "configs/plans").glob("*.yaml")):
        plan = load_plan_source(path).build()
        if plan.is_fly:
            continue
        each = plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages
        each = each + plan.rig.bus_time(plan.travel_s)
        if each.min() < best[1]:
            best = (path.stem, float(each.min()))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(describe())
    print()
    print(
        "| plan | scene | targets | bare devices (µs/sample) | engine + journal (µs/sample) "
        "| overhead (µs/sample) | engine samples/s |"
    )
    print("|---|---|---:|---:|---:|---:|---:|")
    RUNS.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory(dir=RUNS, prefix=".bench-acquire-") as tmp:
        folder = Path(tmp)
        for plan_name, plan_path in PLANS.items():
            source = load_plan_source(plan_path)
            plan = source.build()
            for scene_name, scene_path in SCENES.items():
                scene, text = session.load_scene_file(scene_path, source.rig)
                files = session.Files(
                    source.path,
                    source.text,
                    source.rig.source,
                    source.rig.text,
                    scene_path,
                    text,
                )
                b = min(bare(plan, scene) for _ in range(args.repeat)) / len(plan)
                e = min(engine(files, plan, scene, folder) for _ in range(args.repeat)) / len(plan)
                print(
                    f"| {plan_name} | {scene_name} | {len(plan):,} | {1e6 * b:.0f} | "
                    f"{1e6 * e:.0f} | {1e6 * (e - b):.0f} | {1 / e:,.0f} |"
                )
        load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
        costs = {
            "simulated (synchronous=NORMAL)": [
                commit_costs(folder, False) for _ in range(args.repeat)
            ],
            "durable (synchronous=FULL)": [commit_costs(folder, True) for _ in range(args.repeat)],
            f"bare fsync of {PAGE_BYTES} bytes appended": [
                fsync_costs(folder) for _ in range(args.repeat)
            ],
        }
        load += " → " + ", ".join(f"{x:.2f}" for x in os.getloadavg())
        where = storage(folder)
    name, shortest = shortest_target_s()
    print()
    print(
        "| commit | median per sample (ms) | 90th percentile (ms) | share of the shortest target |"
    )
    print("|---|---:|---:|---:|")
    for label, runs in costs.items():
        every = np.concatenate(runs)
        median, p90 = np.median(every), np.percentile(every, 90)
        print(
            f"| {label} | {1e3 * median:.3f} | {1e3 * p90:.3f} | {100 * median / shortest:.2f} % |"
        )
    print(
        f"\n{args.repeat} × 300 of each in runs/: {where}; load average {load} (1, 5, 15 min) "
        "while they ran"
    )
    print(f"\nshortest target of the shipped stop-and-go plans: {shortest:.3f} s (plan {name!r})")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Acquisition engine costs")
