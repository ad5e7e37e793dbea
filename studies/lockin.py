"""A lock-in amplifier behind a chopper against a DC photodiode read by an ADC, at equal
plan: the quick plan (500 targets, Sobol in the hybrid coordinates, one reading each)
at 50 ms and 5 ms per reading on the arch rig, measuring the matte paint with each
detector's noise (configs/scenes/matte.yaml: shot, read and dark noise, 16-bit ADC;
configs/scenes/matte_lockin.yaml: the same photodiode through 10⁸ V/A into a lock-in at
24 dB/oct, chopper open half the time, the dark current rejected). The lock-in's time
constant τ either follows the exposure (the longest whose settle time, 10.1 τ, fits it:
what the PyMeasure driver sets) or is fixed as on a front panel, when a reading waits
its settle time if that is longer than the exposure. Instrument time is the simulated
run's (moves, settle, readings and calibrations); errors are |recovered / truth − 1|
per target, the median over seeds of each run's median and 95th percentile; σ the
reported relative uncertainty. Then whether that σ is the error when the exposures
vary from target to target (the plan's exposures scaled by the expected signal
within 5 to 80 ms): the standard deviation of (f − truth)/σ per seed. Then the settle time and the
equivalent noise bandwidth per filter slope.

Run: .venv/bin/python studies/lockin.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from drivers.pymeasure import SETTLE_TAU
from gonio.planner import ExposureSpec, build, load_plan
from gonio.progress import hms
from gonio.rig import Rig
from gonio.scene import Scene, load_scene
from gonio.workflows import simulate_plan
from sim.virtual import ENBW_TAU

ROOT = Path(__file__).resolve().parent.parent
SEEDS = (1, 2, 3)


def with_tau(scene: Scene, tau_s: float | None) -> Scene:
    detector = scene.detector.model_copy(update={"time_constant_s": tau_s})
    return scene.model_copy(update={"detector": detector})


def row(label: str, settle: str, plan_path: Path, exposure_s: float, scene: Scene) -> None:
    spec, _ = load_plan(plan_path)
    spec = spec.model_copy(
        update={"exposure": spec.exposure.model_copy(update={"seconds": exposure_s})}
    )
    rig = Rig.from_yaml(ROOT / "configs" / "rigs" / "arch.yaml")
    plan = build(spec, rig)
    medians, p95s, sigmas, times = [], [], [], []
    for seed in SEEDS:
        result = simulate_plan(plan, scene, seed=seed)
        error = np.abs(result.brdf / result.truth - 1.0)
        medians.append(np.median(error))
        p95s.append(np.percentile(error, 95))
        sigmas.append(np.median(result.sigma / result.brdf))
        started = [e.t_s for e in result.run.events] + result.run.samples["ended_s"].tolist()
        times.append(max(started) - min(started))
    print(
        f"| {1000 * exposure_s:g} | {label} | {settle} | {hms(float(np.median(times)))} | "
        f"{100 * np.median(medians):.3f} | {100 * np.median(p95s):.3f} | "
        f"{100 * np.median(sigmas):.3f} |",
        flush=True,
    )


def main_() -> None:
    argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0]).parse_args()
    print(describe())
    plan = ROOT / "configs" / "plans" / "quick.yaml"
    dc = load_scene(ROOT / "configs" / "scenes" / "matte.yaml")
    lockin = load_scene(ROOT / "configs" / "scenes" / "matte_lockin.yaml")
    settle = SETTLE_TAU[24]
    print(
        "\n| exposure (ms) | detector | settle per reading (ms) | instrument time | "
        "median error % | p95 error % | median σ % |"
    )
    print("|---:|---|---:|---:|---:|---:|---:|")
    for exposure in (0.05, 0.005):
        row("DC photodiode, 16-bit ADC", "–", plan, exposure, dc)
        row("lock-in, τ follows the exposure", f"{1000 * exposure:g}", plan, exposure, lockin)
        for tau in (0.001, 0.003, 0.01, 0.03):
            label = f"lock-in, τ = {1000 * tau:g} ms"
            row(label, f"{1000 * settle * tau:.1f}", plan, exposure, with_tau(lockin, tau))
    adapt = {"material": {"name": "lambert", "albedo": 0.5}, "min_s": 0.005, "max_s": 0.08}
    spec, _ = load_plan(plan)
    spec = spec.model_copy(update={"exposure": ExposureSpec(seconds=0.02, adapt=adapt)})
    varied = build(spec, Rig.from_yaml(ROOT / "configs" / "rigs" / "arch.yaml"))
    print("\n| detector | exposures (ms) | std of (f − truth)/σ, seeds 1, 2, 3 |")
    print("|---|---|---|")
    for label, scene in (("DC photodiode", dc), ("lock-in, τ follows the exposure", lockin)):
        spreads = []
        for seed in SEEDS:
            result = simulate_plan(varied, scene, seed=seed)
            z = (result.brdf / result.truth - 1.0) / (result.sigma / result.brdf)
            spreads.append(f"{np.std(z):.2f}")
        span = f"{1000 * varied.exposure_s.min():.0f}–{1000 * varied.exposure_s.max():.0f}"
        print(f"| {label} | {span} | {', '.join(spreads)} |", flush=True)
    print("\n| slope (dB/oct) | settle to 99 % (τ) | noise bandwidth ENBW (1/τ) |")
    print("|---:|---:|---:|")
    for slope, tau in SETTLE_TAU.items():
        print(f"| {slope} | {tau:g} | {ENBW_TAU[slope]:.4f} |")


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="Lock-in amplifier against a DC photodiode")
