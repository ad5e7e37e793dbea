"""Point-source rigs: the error of targets whose detector view runs past the sample's
edge, before and after the planner refuses them. The quick plan (500 targets, Sobol in
the hybrid coordinates) on the arch rig with a lamp 300 mm away (25 mm view, 30 mm
sample, 50.8 mm reference standard), measuring the specular test function of Barla,
Belcour & Pacanowski 2015 with the footprint effect (the lamp lights the holder too;
the simulator integrates over the seen part of the sample plane), with and without
the sensor's noise. "Before": the same plan built by a planner that does not refuse a
view off the sample (the rule the rig applies now, `Reason.VIEW_OFF_SAMPLE`, taken out).
Errors are |recovered / truth − 1| per target; the noise's level is the reported
relative σ.

Run: .venv/bin/python benchmarks/point_source.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio.planner import build, load_plan
from gonio.rig import constraints
from gonio.rig.model import Reason, Rig
from gonio.types import BoolArray, FloatArray
from gonio.workflows.simulate import simulate_plan
from sim.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
NOISE = ["shot_noise", "read_noise", "dark_current", "quantization", "saturation"]


class WithoutViewRefusal(Rig):
    """The rig as planned before: a view off the sample is not a reason to refuse (the
    pair falls through to the later checks, axis limits and collisions)."""

    def _reasons(
        self, wi: FloatArray, wo: FloatArray, limits_ok: BoolArray, usable: BoolArray
    ) -> np.ndarray:
        reasons = super()._reasons(wi, wo, limits_ok, usable)
        view = reasons == Reason.VIEW_OFF_SAMPLE
        later = np.where(
            ~limits_ok.any(axis=0),
            Reason.AXIS_LIMIT,
            np.where(~usable.any(axis=0), Reason.COLLISION, Reason.OK),
        )
        reasons[view] = later[view]
        return reasons


def figures(label: str, rig: Rig, effects: list[str]) -> None:
    spec, _ = load_plan(ROOT / "configs" / "plans" / "quick.yaml")
    plan = build(spec, rig)
    scene = load_scene(ROOT / "configs" / "scenes" / "seed000_specular.yaml", rig)
    result = simulate_plan(plan, scene.with_effects(effects))
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
    for effects in (["footprint"], ["footprint", *NOISE]):
        for label, rig in rigs.items():
            figures(label, rig, effects)


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="Point-source rigs: the view on the sample")
