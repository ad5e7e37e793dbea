"""Simulated acquisition speed: samples per second through `SimMotorBus` + `SimDetector`
(target by target, as the acquisition engine drives them: with the detector prepared
with the plan's poses, and cold) and through the vectorized `sim.virtual.simulate`, for the
shipped quick (500) and isotropic (≈ 5 000) plans, with no effects, with every effect,
and with each effect alone; and the ratio of simulated wall time to the instrument time
the run represents (target ≤ 1/10 000).

Run: .venv/bin/python benchmarks/simulator.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from pathlib import Path

import _report
import numpy as np
from _machine import describe

from gonio import brdf, radiometry
from gonio.planner import Plan, build, load_plan
from gonio.scene import EffectsSpec, Scene, load_scene
from sim.virtual import SimRun, SimulatedInstrument, simulate
from tests.support.measure import measure_targets

ROOT = Path(__file__).resolve().parents[1]


ALL_EFFECTS = {
    "shot_noise": {},
    "read_noise": {},
    "dark_current": {},
    "quantization": {},
    "saturation": {},
    "source_drift": {"rate_per_hour": 0.02, "amplitude": 0.005},
    "aperture_integration": {"order": 6},
    "footprint": {},
    "position_error": {"backlash_deg": 0.1, "repeatability_deg": 0.02},
    "stray_light": {"power_w": 1e-14},
}


def per_sample(plan: Plan, scene: Scene) -> SimRun:
    """Target by target through the protocols, the detector prepared with the poses."""
    with SimulatedInstrument(scene, plan.rig) as inst:
        return measure_targets(inst, plan)


def per_sample_cold(plan: Plan, scene: Scene) -> SimRun:
    """The same without preparing: the chain evaluated for each pose alone."""
    with SimulatedInstrument(scene, plan.rig) as inst:
        return measure_targets(inst, plan, prepare=False)


def timed(run: Callable[[], SimRun], repeat: int) -> tuple[float, SimRun]:
    best, result = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - t)
    assert result is not None
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    base = load_scene(ROOT / "configs/scenes/glossy_metal.yaml")
    scenes = {"none": base.with_effects([]), "all": base.with_effects(ALL_EFFECTS)}
    plans = {}
    for name in ("quick", "isotropic_hybrid"):
        spec, rig = load_plan(ROOT / f"configs/plans/{name}.yaml")
        plans[name] = build(spec, rig)
    print(describe())
    print()
    print(
        "| plan | targets | effects | path | samples/s | wall (s) | instrument time "
        "| wall / instrument |"
    )
    print("|---|---:|---|---|---:|---:|---:|---:|")
    for plan_name, plan in plans.items():
        for label, scene in scenes.items():
            paths = (
                ("per sample", per_sample),
                ("per sample, cold", per_sample_cold),
                ("vectorized", simulate),
            )
            for path, run in paths:
                wall, result = timed(lambda r=run, s=scene, p=plan: r(p, s), args.repeat)
                hours = result.instrument_time_s / 3600
                print(
                    f"| {plan_name} | {len(plan)} | {label} | {path} | {len(plan) / wall:,.0f} "
                    f"| {wall:.3f} | {hours:.2f} h | 1/{result.instrument_time_s / wall:,.0f} |",
                    flush=True,
                )
    plan = plans["quick"]
    print()
    print(
        "Each effect alone, quick plan (µs per sample; the no-effect cost subtracted in 'extra'):"
    )
    print()
    print("| effect | per sample (µs) | extra (µs) | vectorized (µs) | extra (µs) |")
    print("|---|---:|---:|---:|---:|")
    t_none = timed(lambda: per_sample(plan, scenes["none"]), args.repeat)[0] / len(plan) * 1e6
    v_none = timed(lambda: simulate(plan, scenes["none"]), args.repeat)[0] / len(plan) * 1e6
    print(f"| none | {t_none:.1f} | 0 | {v_none:.2f} | 0 |")
    for name, params in ALL_EFFECTS.items():
        scene = base.with_effects(EffectsSpec.model_validate({name: params}))
        t = timed(lambda s=scene: per_sample(plan, s), args.repeat)[0] / len(plan) * 1e6
        v = timed(lambda s=scene: simulate(plan, s), args.repeat)[0] / len(plan) * 1e6
        print(f"| {name} | {t:.1f} | {t - t_none:+.1f} | {v:.2f} | {v - v_none:+.2f} |", flush=True)


def aperture_orders() -> None:
    """Relative error of the aperture integral of a sharp GGX peak (α = 0.02, θi = 30°,
    1° off the mirror direction) at the orders a scene may choose, against order 48."""
    model = brdf.create("cook_torrance", alpha=0.02, fresnel="schlick", f0=0.9)
    t, o = math.radians(30.0), math.radians(31.0)
    wi = np.array([[math.sin(t), 0.0, math.cos(t)]])
    wo = np.array([[-math.sin(o), 0.0, math.cos(o)]])
    orders = (4, 6, 8, 12)
    print()
    print("Aperture quadrature, relative error against order 48 (GGX α = 0.02, 1° off peak):")
    print()
    print("| aperture | " + " | ".join(f"order {n}" for n in orders) + " |")
    print("|---|" + "---:|" * len(orders))
    for aperture in (1e-5, 1e-4, 1e-3):
        exact = radiometry.aperture_integral(model.eval, wi, wo, aperture, "cos", order=48)
        errors = [
            abs(
                radiometry.aperture_integral(model.eval, wi, wo, aperture, "cos", order=n) / exact
                - 1
            )[0]
            for n in orders
        ]
        print(f"| {aperture:g} sr | " + " | ".join(f"{e:.0e}" for e in errors) + " |")


def both() -> None:
    main()
    aperture_orders()


if __name__ == "__main__":
    _report.run(both, __file__, __doc__, title="Simulated acquisition speed")
