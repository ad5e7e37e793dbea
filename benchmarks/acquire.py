"""Acquisition engine costs.

1. Engine + journal overhead per sample on the simulated backend: `gonio acquire`'s
   loop (limits, measure, saturation check, journal row with FK of the read-back
   angles and the simulator's snapshot, one committed SQLite transaction per sample)
   against the bare simulated devices measuring the same targets one by one
   (`SimulatedInstrument.run`, the same `measure_target` step, no journal), both with
   the detector's optics precomputed. Targets: overhead ≤ 200 µs per sample, and
   ≥ 2 000 samples/s with the demo's effects (the glossy-metal scene).
2. The durable commit (hardware path: `synchronous=FULL`, one fsync'ed WAL commit per
   sample) against the plain one (simulated backend), per sample, on this disk; and
   that cost as a share of the shortest target of the shipped plans (move + settle +
   exposure; target ≤ 2 %).

Run: .venv/bin/python benchmarks/acquire.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import _report
import numpy as np
from _machine import describe

from gonio.planner import load_plan_source
from gonio.planner.model import Plan
from gonio.store.journal import Journal
from gonio.store.schema import samples_table
from gonio.workflows import session
from gonio.workflows.simulate import measure_targets
from sim.devices.instrument import SimulatedInstrument
from sim.scene import Scene

ROOT = Path(__file__).resolve().parents[1]
PLANS = {
    "quickstart": ROOT / "configs/plans/quickstart.yaml",
    "isotropic": ROOT / "configs/plans/isotropic_hybrid.yaml",
}
SCENES = {
    "matte": ROOT / "configs/scenes/matte.yaml",
    "glossy": ROOT / "configs/scenes/glossy_metal.yaml",
}


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


def commit_cost(folder: Path, durable: bool, n: int = 300) -> float:
    """Seconds per committed sample row."""
    axes, coords = ["a", "b", "c", "d"], ["x", "y", "z"]
    meta = {"axes": axes, "coordinate_names": coords}
    path = folder / f"commit-{durable}.sqlite"
    path.unlink(missing_ok=True)
    row = dict.fromkeys((c.name for c in samples_table(axes, coords)), 0.5)
    row.update(utc="2026-01-01T00:00:00", temperatures_c=None, sim_state=None)
    with Journal.create(path, meta, b"", durable=durable, overwrite=True) as journal:
        journal.start_session("t", {})
        t = time.perf_counter()
        for i in range(n):
            journal.sample({**row, "target": i})
        return (time.perf_counter() - t) / n


def shortest_target_s() -> tuple[str, float]:
    best = ("", np.inf)
    for path in sorted((ROOT / "configs/plans").glob("*.yaml")):
        plan = load_plan_source(path).build()
        each = plan.travel_s + plan.rig.spec.settle_s + plan.exposure_s * plan.averages
        if each.min() < best[1]:
            best = (path.stem, float(each.min()))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(describe())
    print()
    print("| plan | scene | targets | bare devices (µs/sample) | engine + journal (µs/sample) "
          "| overhead (µs/sample) | engine samples/s |")  # fmt: skip
    print("|---|---|---:|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for plan_name, plan_path in PLANS.items():
            source = load_plan_source(plan_path)
            plan = source.build()
            for scene_name, scene_path in SCENES.items():
                scene, text = session.load_scene_file(scene_path, source.rig)
                files = session.Files(
                    source.path, source.text, source.rig.source, source.rig.text,
                    scene_path, text,
                )  # fmt: skip
                b = min(bare(plan, scene) for _ in range(args.repeat)) / len(plan)
                e = min(engine(files, plan, scene, folder) for _ in range(args.repeat)) / len(plan)
                print(
                    f"| {plan_name} | {scene_name} | {len(plan):,} | {1e6 * b:.0f} | "
                    f"{1e6 * e:.0f} | {1e6 * (e - b):.0f} | {1 / e:,.0f} |"
                )
        plain = min(commit_cost(folder, False) for _ in range(args.repeat))
        durable = min(commit_cost(folder, True) for _ in range(args.repeat))
    name, shortest = shortest_target_s()
    print()
    print("| commit | per sample (ms) | share of the shortest target |")
    print("|---|---:|---:|")
    for label, cost in (("simulated (synchronous=NORMAL)", plain), ("durable (FULL)", durable)):
        print(f"| {label} | {1e3 * cost:.3f} | {100 * cost / shortest:.2f} % |")
    print(f"\nshortest target of the shipped plans: {shortest:.3f} s (plan {name!r})")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Acquisition engine costs")
