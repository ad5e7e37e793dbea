"""The naive reference's scores (the floor of every method): simulated runs of uniform plans on
the shipped scenes (their noise on), reconstructed by `gonio.reconstruct.naive` and scored
against their scene by `gonio.reconstruct.evaluate` on the default test set, with the
time each step takes.

Run: .venv/bin/python studies/evaluation.py [--targets 300 1000 3000]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import yaml
from _machine import describe

from gonio.analysis import Measured
from gonio.cli import main
from gonio.reconstruct import NaiveReconstruction, evaluate, testset, truth_from_spec

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"matte": "matte.yaml", "glossy metal": "glossy_metal.yaml"}


def plan(targets: int) -> dict[str, Any]:
    return {
        "name": f"bench-{targets}",
        "rig": str(ROOT / "configs/rigs/arch.yaml"),
        "parametrization": "hybrid",
        "isotropic": True,
        "sampling": {"strategy": "sobol", "target": targets, "seed": 3},
        "exposure": {"seconds": 0.05, "averages": 1},
        "time_budget_s": 60,
        "acquisition": {"calibration": {"every_samples": 500, "dark": True, "averages": 16}},
    }


def acquire(folder: Path, targets: int, scene: str) -> Path:
    plan_file, out = folder / f"plan-{targets}.yaml", folder / f"{scene}-{targets}.sqlite"
    plan_file.write_text(yaml.safe_dump(plan(targets)))
    scene_file = str(ROOT / "configs/scenes" / scene)
    with contextlib.redirect_stdout(io.StringIO()):  # the plan's and the run's summaries
        code = main(["acquire", str(plan_file), "--scene", scene_file, "-o", str(out), "-q"])
    assert code == 0, f"gonio acquire exited {code}"
    return out


def main_() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--targets", type=int, nargs="+", default=[300, 1000, 3000])
    args = parser.parse_args()
    print(describe())
    t = time.perf_counter()
    pairs = testset.draw(_arch(), isotropic=True)
    print(f"test set: {len(pairs)} pairs drawn in {time.perf_counter() - t:.2f} s\n")
    head = (
        f"{'scene':13} {'samples':>7} {'region':8} {'coverage':>8} {'log-RMSE':>9} "
        f"{'cos log':>8} {'rel med':>8} {'rel p95':>8} {'build s':>8} {'score s':>8}"
    )
    print(head)
    with tempfile.TemporaryDirectory() as tmp:
        for label, scene in SCENES.items():
            for targets in args.targets:
                m = Measured.from_run(acquire(Path(tmp), targets, scene))
                t0 = time.perf_counter()
                naive = NaiveReconstruction(m)
                t1 = time.perf_counter()
                result = evaluate(
                    naive, truth_from_spec(None, m), m.rig, isotropic=True, test_set=pairs
                )
                t2 = time.perf_counter()
                for region in ("all", "mirror", "grazing"):
                    r = result.regions[region]
                    s = r.scores
                    print(
                        f"{label:13} {len(m):7d} {region:8} {100 * (r.coverage or 0):7.1f}% "
                        f"{s.log_rmse or 0:9.4f} {s.cos_log_rmse or 0:8.4f} "
                        f"{s.rel_median or 0:8.4f} {s.rel_p95 or 0:8.3f} "
                        f"{t1 - t0:8.3f} {t2 - t1:8.3f}"
                    )


def _arch() -> Any:
    from gonio.rig import Rig

    return Rig.from_yaml(ROOT / "configs/rigs/arch.yaml")


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="The naive reference's scores")
