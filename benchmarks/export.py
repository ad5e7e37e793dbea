"""Export times: `gonio export` of a simulated run of 20 000 samples (Sobol,
uniform in the hybrid coordinates, the glossy metal scene with its noise) in every
format, each timed in this process (the run file is read and, for merl, factored and
hdf5 --grid, reconstructed by `linear`); then `gonio export --format merl` of a
simulated grid run (24³ = 13 824 targets at cell centres in Rusinkiewicz's
coordinates, those the arch rig reaches measured; the glossy metal scene with GGX
α 0.1), timed end to end as a command (a new process: start-up, reading, the linear
reconstruction, the 1.46 million bins filled and written; a grid's cospherical points
make flat simplices, which the Delaunay walk must cross). Bound: every merl export
under 20 s on the 2-core machine; the script fails above it.

Run: .venv/bin/python benchmarks/export.py [--targets 20000] [--run RUN.sqlite]
[--grid-run RUN.sqlite]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio.cli import main
from gonio.store import open_run

ROOT = Path(__file__).resolve().parent.parent
#: Points per Rusinkiewicz coordinate of the grid run.
GRID = 24
FORMATS: list[tuple[str, list[str]]] = [
    ("csv", []),
    ("alta", []),
    ("bluesky", []),
    ("hdf5", []),
    ("hdf5", ["--grid", "hybrid", "--grid-points", "32"]),
    ("merl", []),
    ("factored", ["--outer", "2", "--inner", "2"]),
]


def stated_bound(doc: str) -> float:
    """The bound the page states (the docstring's "under N s"), in seconds."""
    found = re.search(r"under (\d+) s", " ".join(doc.split()))
    if found is None:
        raise SystemExit("the docstring states no bound (under N s)")
    return float(found[1])


def acquire(folder: Path, targets: int) -> Path:
    plan = {
        "name": f"export-{targets}",
        "rig": str(ROOT / "configs/rigs/arch.yaml"),
        "sampling": {"strategy": "sobol", "target": targets, "seed": 3},
        "exposure": {"seconds": 0.05},
        "kicks": 0,
        "time_budget_s": 120,
    }
    (folder / "plan.yaml").write_text(yaml.safe_dump(plan))
    out = folder / "run.sqlite"
    args = ["acquire", str(folder / "plan.yaml"), "--scene"]
    args += [str(ROOT / "configs/scenes/glossy_metal.yaml"), "-o", str(out), "-q"]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(args) == 0
    return out


def grid_run(folder: Path) -> Path:
    """`gonio simulate` of the 24³ grid plan on the glossy metal scene at GGX α 0.1."""
    plan = {
        "name": f"grid-{GRID}",
        "rig": str(ROOT / "configs/rigs/arch.yaml"),
        "parametrization": "rusinkiewicz",
        "isotropic": True,
        "sampling": {
            "strategy": "grid",
            "counts": {"theta_h": GRID, "theta_d": GRID, "phi_d": GRID},
        },
        "exposure": {"seconds": 0.05},
        "time_budget_s": 36_000,
    }
    scene = yaml.safe_load((ROOT / "configs/scenes/glossy_metal.yaml").read_text())
    scene["name"] = "glossy-metal-0.1"
    scene["material"]["alpha"] = 0.1
    (folder / "grid.yaml").write_text(yaml.safe_dump(plan))
    (folder / "scene.yaml").write_text(yaml.safe_dump(scene))
    out = folder / "grid.sqlite"
    args = ["simulate", str(folder / "grid.yaml"), "--scene", str(folder / "scene.yaml")]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([*args, "-o", str(out), "-q"]) == 0
    return out


def command_time(args: list[str]) -> float:
    """Wall seconds of ``gonio ARGS`` run as a command (a new Python process)."""
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "gonio", *args], cwd=ROOT, capture_output=True, text=True
    )
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"gonio {' '.join(args)} failed: {done.stderr.strip()}")
    return wall


def main_() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--targets", type=int, default=20_000)
    parser.add_argument("--run", type=Path, help="an existing run file instead")
    parser.add_argument("--grid-run", type=Path, help="an existing grid run file instead")
    args = parser.parse_args()
    bound = stated_bound(__doc__ or "")
    print(describe())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        started = time.perf_counter()
        run = args.run or acquire(folder, args.targets)
        if args.run is None:
            print(f"acquired {args.targets:,} samples in {time.perf_counter() - started:.0f} s")
        print("\n| format | options | time (s) | size (MB) | load (1 min) |")
        print("|---|---|---:|---:|---:|")
        merl: dict[str, float] = {}
        for name, options in FORMATS:
            out = folder / f"out.{name}"
            load = os.getloadavg()[0]
            started = time.perf_counter()
            code = main(["export", str(run), "--format", name, "-o", str(out), "-q", *options])
            wall = time.perf_counter() - started
            assert code == 0, name
            size = sum(p.stat().st_size for p in folder.glob(f"out.{name}*"))
            shown = " ".join(options) or "—"
            print(f"| {name} | {shown} | {wall:.1f} | {size / 1e6:.1f} | {load:.2f} |", flush=True)
            for p in folder.glob(f"out.{name}*"):
                p.unlink()
            if name == "merl":
                merl[f"the {args.targets:,}-sample Sobol run, in this process"] = wall

        started = time.perf_counter()
        grid = args.grid_run or grid_run(folder)
        if args.grid_run is None:
            print(f"\nsimulated the {GRID}³ grid run in {time.perf_counter() - started:.0f} s")
        samples = len(open_run(grid))
        out = folder / "grid.binary"
        load = os.getloadavg()[0]
        wall = command_time(["export", str(grid), "--format", "merl", "-o", str(out), "-q"])
        what = f"the {GRID}³ grid run ({samples:,} samples), end to end"
        merl[what] = wall
        print("\n| merl export of | time (s) | load (1 min) |")
        print("|---|---:|---:|")
        print(f"| {what} | {wall:.1f} | {load:.2f} |")
    over = "; ".join(f"{what}: {wall:.1f} s" for what, wall in merl.items() if wall > bound)
    if over:
        raise SystemExit(f"merl export over the bound of {bound:.0f} s: {over}")
    print(f"\nevery merl export under the bound of {bound:.0f} s")


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="Export times")
