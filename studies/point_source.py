"""Point-source rigs: the error of targets whose detector view runs past the sample's
edge, before and after the planner refuses them. The quick plan (500 targets, Sobol in
the hybrid coordinates) on the arch rig with a lamp 300 mm away (25 mm view, 30 mm
sample, 50.8 mm reference standard), measuring the specular test function of Barla,
Belcour & Pacanowski 2015 with the footprint effect (the lamp lights the holder too;
the simulator integrates over the seen part of the sample plane), with and without
the sensor's noise. "Before": the same plan built by a planner that does not refuse a
view off the sample (the rule the rig applies now, `Reason.VIEW_OFF_SAMPLE`, taken out).
Errors are |recovered / truth − 1| per target, the analysis's calibrated values (the
spot fall-off divided out: the simulated holder is dark, so a view past the sample's
edge is corrected too, which a lit holder on hardware would not allow); the noise's
level is the reported relative σ.

Second table: on the targets whose view is on the sample (the planner "after"), the
recovered BRDF without and with the analysis's correction of the lamp's spot fall-off
(`gonio.analysis.falloff`: the irradiance falling off across the seen spot and the
BRDF varying over its spread of incidence, divided out; the correction's own error in
σ). |error|/σ is per target; its 95th percentile is within 2 where the σ are right.

Run: .venv/bin/python studies/point_source.py
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

from gonio.analysis import calibrate
from gonio.planner import build, load_plan
from gonio.rig import Reason, Refusals, Rig, constraints
from gonio.scene import load_scene
from gonio.types import BoolArray, FloatArray
from gonio.workflows import Result, simulate_plan

ROOT = Path(__file__).resolve().parent.parent
NOISE = ["shot_noise", "read_noise", "dark_current", "quantization", "saturation"]


class WithoutViewRefusals(Refusals):
    """The refusals as planned before: a view off the sample is not a reason to refuse
    (the pair falls through to the later checks, axis limits and collisions)."""

    def reasons(
        self, wi: FloatArray, wo: FloatArray, limits_ok: BoolArray, usable: BoolArray
    ) -> np.ndarray:
        reasons = super().reasons(wi, wo, limits_ok, usable)
        view = reasons == Reason.VIEW_OFF_SAMPLE
        later = np.where(
            ~limits_ok.any(axis=0),
            Reason.AXIS_LIMIT,
            np.where(~usable.any(axis=0), Reason.COLLISION, Reason.OK),
        )
        reasons[view] = later[view]
        return reasons


class WithoutViewRefusal(Rig):
    """The rig as planned before (`WithoutViewRefusals`)."""

    refusals_type = WithoutViewRefusals


def measure(rig: Rig, effects: list[str]) -> Result:
    spec, _ = load_plan(ROOT / "configs" / "plans" / "quick.yaml")
    plan = build(spec, rig)
    scene = load_scene(ROOT / "configs" / "scenes" / "seed000_specular.yaml", rig)
    return simulate_plan(plan, scene.with_effects(effects))


def figures(label: str, rig: Rig, effects: list[str], result: Result) -> None:
    plan = result.plan
    c = rig.spec.constraints
    on = constraints.view_on_sample(result.true_wo, c.detector_fov_mm, c.sample_diameter_mm)
    error = np.abs(result.brdf / result.truth - 1.0)
    sigma = result.sigma / result.brdf
    noise = f"{100 * np.median(sigma):.3f} / {100 * np.percentile(sigma, 95):.3f}"
    refused = plan.summary.refused.get(Reason.VIEW_OFF_SAMPLE.label, 0)
    for which, mask in (("all", np.ones_like(on)), ("view on the sample", on), ("off", ~on)):
        if not mask.any():
            continue
        e = error[mask]
        print(
            f"| {label} | {'+'.join(effects)} | {refused} | {which} | {mask.sum()} | "
            f"{100 * np.median(e):.3f} | {100 * np.percentile(e, 95):.3f} | "
            f"{100 * e.max():.3f} | {noise} |",
            flush=True,
        )


def main_() -> None:
    argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0]).parse_args()
    print(describe())
    path = ROOT / "configs" / "rigs" / "arch_point.yaml"
    rigs = {"before": WithoutViewRefusal.from_yaml(path), "after": Rig.from_yaml(path)}
    print(
        "\n| planner | effects | refused (view) | targets | n | median error % | "
        "p95 error % | max error % | noise σ % (median / p95) |"
    )
    print("|---|---|---:|---|---:|---:|---:|---:|---|")
    kept: dict[str, Result] = {}
    for effects in (["footprint"], ["footprint", *NOISE]):
        for label, rig in rigs.items():
            result = measure(rig, effects)
            figures(label, rig, effects, result)
            if label == "after":
                kept["+".join(effects)] = result
    print(
        "\n| effects | fall-off correction | n | median error % | p95 error % | max error % | "
        "σ % (median / p95) | p95 of abs(error)/σ |"
    )
    print("|---|---|---:|---:|---:|---:|---|---:|")
    for effects_label, result in kept.items():
        for which in ("without", "with"):
            correction(effects_label, which, result)


def correction(effects: str, which: str, result: Result) -> None:
    """One row of the second table: the run calibrated without or with the correction."""
    calibrated = calibrate(result.run, falloff=which == "with")
    error = np.abs(calibrated.brdf / result.truth - 1.0)
    sigma = calibrated.sigma / calibrated.brdf
    z = error / sigma
    print(
        f"| {effects} | {which} | {error.size} | {100 * np.median(error):.3f} | "
        f"{100 * np.percentile(error, 95):.3f} | {100 * error.max():.3f} | "
        f"{100 * np.median(sigma):.3f} / {100 * np.percentile(sigma, 95):.3f} | "
        f"{np.percentile(z, 95):.2f} |",
        flush=True,
    )


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="Point-source rigs: the view on the sample")
