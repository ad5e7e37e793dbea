"""Fly plans against stop-and-go, as the planner predicts them: readings per instrument
hour of `sampling.strategy: fly` plans (the detector's arc sweeping at constant velocity
through anchors uniform in Rusinkiewicz's isotropic coordinates, the photometer streaming
100 readings a second of 10 ms each, about --readings readings) on the arch and in-plane
rigs at a few blur tolerances; against the same readings measured stop-and-go (a move, the rig's
settle and one 10 ms integration each, in the same order) and against a uniform (Sobol)
stop-and-go plan of --uniform targets ordered by the planner with the same exposure. The
readings are those the planner keeps of the stream (thinned to the uniform density;
"streamed" the detector's readings). The coverage column is the total-variation distance
between the kept readings' histogram (8 bins a coordinate) and the uniform density over
what the rig reaches; "uniform TV" is the same figure for a Sobol plan of as many
targets (its sampling noise); "gap" the radius of the largest empty ball (unit box)
centred on a reachable point, against the Sobol plan's. A second table varies the
reading rate at a 0.5° blur budget: fewer readings per sweep, more sweeps.
Predictions of the planner's timing model (gonio.planner.fly), not measured motion.

Run: .venv/bin/python benchmarks/fly_plan.py [--readings 20000] [--uniform 2000]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio.planner import Plan, PlanSpec, build
from gonio.rig import Rig

ROOT = Path(__file__).resolve().parent.parent
RIGS = {"arch": ROOT / "configs/rigs/arch.yaml", "in-plane": ROOT / "configs/rigs/in_plane.yaml"}
BLURS = (0.1, 0.25, 0.5, 1.0)
RATES = (100.0, 50.0, 25.0, 10.0)
INTEGRATION_S = 0.01


def fly_plan(rig: Rig, readings: int, blur: float, rate: float) -> Plan:
    spec: dict[str, Any] = {
        "name": "fly",
        "parametrization": "rusinkiewicz",
        "sampling": {
            "strategy": "fly",
            "target": readings,
            "seed": 1,
            "fly": {"rate_hz": rate, "integration_s": INTEGRATION_S, "blur_deg": blur},
        },
    }
    return build(PlanSpec.model_validate(spec), rig)


def uniform_plan(rig: Rig, targets: int) -> Plan:
    spec: dict[str, Any] = {
        "name": "uniform",
        "parametrization": "rusinkiewicz",
        "sampling": {"strategy": "sobol", "target": targets, "seed": 1},
        "exposure": {"seconds": INTEGRATION_S},
    }
    return build(PlanSpec.model_validate(spec), rig)


def per_hour(count: int, seconds: float) -> float:
    return 3600.0 * count / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--readings", type=int, default=20_000)
    parser.add_argument("--uniform", type=int, default=2_000)
    args = parser.parse_args()
    print(describe())
    rigs = {name: Rig.from_yaml(path) for name, path in RIGS.items()}
    uniform = {}
    for name, rig in rigs.items():
        started = time.perf_counter()
        plan = uniform_plan(rig, args.uniform)
        uniform[name] = per_hour(len(plan), plan.summary.total_s)
        print(
            f"{name}: a uniform Sobol stop-and-go plan of {len(plan)} targets, 10 ms each, "
            f"takes {plan.summary.total_s / 60:.1f} min: {uniform[name]:,.0f} targets per "
            f"hour (planned in {time.perf_counter() - started:.1f} s)"
        )
    print(f"\n## Blur budget ({args.readings:,} readings, 100 Hz, 10 ms each)\n")
    header = (
        "| rig | blur (°) | sweeps | velocity (°/s) | readings | duration (min) | "
        "streamed | readings/h fly | same readings stop-and-go /h | × | uniform stop-and-go /h "
        "| × | coverage TV | uniform TV | gap | uniform gap |"
    )
    print(header)
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, rig in rigs.items():
        for blur in BLURS:
            print(row(name, fly_plan(rig, args.readings, blur, 100.0), blur, uniform), flush=True)
    print(f"\n## Reading rate (blur 0.5°, {args.readings:,} readings, 10 ms each)\n")
    print(header.replace("blur (°)", "rate (Hz)"))
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, rig in rigs.items():
        for rate in RATES:
            print(row(name, fly_plan(rig, args.readings, 0.5, rate), rate, uniform), flush=True)


def row(name: str, plan: Plan, knob: float, uniform: dict[str, float]) -> str:
    s = plan.summary
    f = s.fly
    assert f is not None
    fly = per_hour(s.kept, s.total_s)
    same = per_hour(s.kept, f.stop_and_go_s)
    speeds = (
        f"{f.velocity_max_deg_s:.3g}"
        if f.velocity_max_deg_s - f.velocity_min_deg_s < 1e-9
        else f"{f.velocity_min_deg_s:.3g}–{f.velocity_max_deg_s:.3g}"
    )
    return (
        f"| {name} | {knob:g} | {f.segments} | {speeds} | {s.kept:,} | {s.total_s / 60:.1f} | "
        f"{f.streamed:,} | {fly:,.0f} | {same:,.0f} | {fly / same:.1f} | {uniform[name]:,.0f} | "
        f"{fly / uniform[name]:.1f} | {f.coverage_tv:.3f} | {f.coverage_tv_uniform:.3f} | "
        f"{f.coverage_gap:.3f} | {f.coverage_gap_uniform:.3f} |"
    )


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="Fly plans against stop-and-go (predicted)")
