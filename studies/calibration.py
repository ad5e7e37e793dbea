"""The calibration's scale error against its predicted σ, over many seeds.

Each seed is one simulated run's calibrations: reference and dark readings at the arch
rig's 0°/45° geometry, taken as the engine takes them (`sim.virtual.simulate.simulate_standard`,
its readings bit for bit), journaled and turned into the run's calibration series by
`gonio.analysis.calibrated`. The scale error is the mean over the run's time of
S_true/S − 1 (S the interpolated reference rate every value is divided by, S_true the
simulator's noise-free rate); its predicted σ is `gonio.analysis.shared`'s. Printed per
case: the z-scores' (error / σ) mean, standard deviation and RMS, now and under the
former model (a straight line between calibrations, and no term for the dark readings'
rounding to ADC codes), which the same readings are also put through. 1 ± 0.2 is the
target; "short" is 3 calibrations of 16 exposures 20 s apart, "long" 21 of 64; "drift"
is the brushed-metal scene's (2 %/h and 0.5 % over 15 min); "dark drawn" moves the dark
level per seed by a uniform fraction of an ADC code (the rounding term's variance is
the mean over where the level sits in its code; a scene's level sits at one place).
Then the glossy scene at every exposure count a reading may have (the plan's 4 to 1000),
calibrated 2 or 3 times: the noise model rests on ν = K·(n − 1) degrees of freedom and
σ carries Student's factor ν/(ν − 2) on its variance (`gonio.analysis.calibrated`);
printed beside it, the z-scores without that factor, whose spread it predicts as
sqrt(ν/(ν − 2)) (the dark level drawn per seed, as in "dark drawn"). Then
what isolates each cause: the dark reading's rounding bias in the shipped scenes, and
the straight line's error on a noise-free drifting run.

Run: .venv/bin/python studies/calibration.py [--seeds 1000]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.support
import _report
import numpy as np
from _machine import describe

from gonio.acquire import reference_pose
from gonio.rig import Rig
from gonio.scene import Scene
from sim.virtual import expected_rate, sensor_of
from tests.support.calibration import calibration_events, scale_errors
from tests.support.runs import RIGS, scene_spec

#: The brushed-metal scene's drift (configs/scenes/brushed_metal.yaml).
DRIFT = {"rate_per_hour": 0.02, "amplitude": 0.005, "period_s": 900}
SHORT: dict[str, Any] = {"calibrations": 3, "averages": 16}
LONG: dict[str, Any] = {"calibrations": 21, "averages": 64}
CASES: list[tuple[str, str, bool, dict[str, Any]]] = [
    ("matte, short", "matte", False, SHORT),
    ("glossy, short", "glossy_metal", False, SHORT),
    ("matte, long", "matte", False, LONG),
    ("glossy, long", "glossy_metal", False, LONG),
    ("matte, long, dark drawn", "matte", False, LONG | {"dark_step": True}),
    ("glossy, long, dark drawn", "glossy_metal", False, LONG | {"dark_step": True}),
    ("matte, drift, short, 120 s apart", "matte", True, SHORT | {"interval_s": 120.0}),
    ("glossy, drift, short, 120 s apart", "glossy_metal", True, SHORT | {"interval_s": 120.0}),
    ("glossy, drift, long, 120 s apart", "glossy_metal", True, LONG | {"interval_s": 120.0}),
    (
        "matte, drift, long, 120 s apart, dark drawn",
        "matte",
        True,
        LONG | {"interval_s": 120.0, "dark_step": True},
    ),
    (
        "glossy, drift, long, 120 s apart, dark drawn",
        "glossy_metal",
        True,
        LONG | {"interval_s": 120.0, "dark_step": True},
    ),
]
#: Exposures a calibration reading: from the plan schema's least (4) to its most (1000).
EXPOSURES = (4, 5, 6, 8, 12, 16, 32, 64, 1000)


def scene(name: str, drift: bool, *, effects: list[str] | None = None) -> Scene:
    spec = scene_spec(name, effects=effects)
    if drift:
        spec["effects"]["source_drift"] = DRIFT
    return Scene.model_validate(spec)


def spreads(rig: Rig, seeds: range) -> None:
    print("| case | seeds | z mean | z std | z RMS | former: mean | std | RMS | σ (median) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, name, drift, schedule in CASES:
        r = scale_errors(rig, scene(name, drift), seeds, linear=True, **schedule)
        assert r.linear is not None
        now, before = r.spread(), r.linear.spread()
        print(
            f"| {label} | {len(seeds)} | {now['mean']:+.2f} | {now['std']:.2f} | {now['rms']:.2f} "
            f"| {before['mean']:+.2f} | {before['std']:.2f} | {before['rms']:.2f} "
            f"| {np.median(r.sigma):.2g} |"
        )


def exposure_counts(rig: Rig, seeds: range) -> None:
    """The glossy scene at every exposure count, calibrated at the start and the end (2)
    or 3 times, 20 s apart, its dark level drawn per seed: ν = K·(n − 1)."""
    print()
    print(
        "| exposures | calibrations | ν | sqrt(ν/(ν−2)) | z mean | z std | z RMS "
        "| without the factor: std | RMS |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    sc = scene("glossy_metal", False)
    for n in EXPOSURES:
        for k in (2, 3):
            r = scale_errors(rig, sc, seeds, averages=n, calibrations=k, dark_step=True)
            assert r.unexpanded is not None
            now = r.spread()
            bare = r.error / r.unexpanded
            nu = k * (n - 1)
            print(
                f"| {n} | {k} | {nu} | {np.sqrt(nu / (nu - 2)):.3f} | {now['mean']:+.2f} "
                f"| {now['std']:.2f} | {now['rms']:.2f} | {np.std(bare, ddof=1):.2f} "
                f"| {np.sqrt(np.mean(bare**2)):.2f} |"
            )


def dark_bias(rig: Rig, seeds: range) -> None:
    """The dark readings' mean against the true dark level, in ADC codes."""
    print()
    print("| scene | dark level (codes) | mean dark reading | rounding bias | of S | σ per code |")
    print("|---|---|---|---|---|---|")
    pose = reference_pose(rig)
    for name in ("matte", "glossy_metal"):
        sc = scene(name, False)
        spec, _ = sensor_of(sc)
        level = spec.dark_current_e_s * 0.05 / spec.gain_e_per_count
        noise = np.sqrt(spec.dark_current_e_s * 0.05 + spec.read_noise_e**2) / spec.gain_e_per_count
        darks = [
            e.data["dark"]["value"] for s in seeds for e in calibration_events(rig, sc, s, **LONG)
        ]
        bias = float(np.mean(darks)) - level
        rate = float(expected_rate(rig, sc, pose, np.array([0.0]))[0]) * 0.05
        print(
            f"| {name} | {level:.3f} | {np.mean(darks):.3f} | {bias:+.3f} | {-bias / rate:+.2g} "
            f"| {noise:.3f} |"
        )


def drift_line(rig: Rig) -> None:
    """The interpolation's own error: a run with the drift and no noise."""
    print()
    print("| noise-free drifting run, 120 s apart | calibrations | scale error now | former |")
    print("|---|---|---|---|")
    for calibrations in (3, 5, 21):
        sc = scene("glossy_metal", True, effects=[])
        sc = sc.with_effects({"source_drift": DRIFT})
        r = scale_errors(
            rig, sc, range(1), linear=True, calibrations=calibrations, interval_s=120.0
        )
        assert r.linear is not None
        print(f"| glossy | {calibrations} | {r.error[0]:+.2g} | {r.linear.error[0]:+.2g} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=1000)
    args = parser.parse_args()
    print(describe())
    rig = Rig.from_yaml(RIGS / "arch.yaml")
    start = time.process_time()
    spreads(rig, range(args.seeds))
    exposure_counts(rig, range(args.seeds))
    dark_bias(rig, range(min(args.seeds, 200)))
    drift_line(rig)
    print(f"\nCPU {time.process_time() - start:.1f} s")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="The calibration's scale error over many seeds")
