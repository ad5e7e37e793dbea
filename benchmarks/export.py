"""Export times: `gonio export` of a simulated run of 20 000 samples (Sobol,
uniform in the hybrid coordinates, the glossy metal scene with its noise) in every
format, each timed in this process (the run file is read and, for merl, factored and
hdf5 --grid, reconstructed by `linear`); target: merl < 20 s on the 2-core machine.

Run: .venv/bin/python benchmarks/export.py [--targets 20000] [--run RUN.sqlite]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _report
from _machine import describe

from gonio.cli import main

ROOT = Path(__file__).resolve().parent.parent
FORMATS: list[tuple[str, list[str]]] = [
    ("csv", []),
    ("alta", []),
    ("bluesky", []),
    ("hdf5", []),
    ("hdf5", ["--grid", "hybrid", "--grid-points", "32"]),
    ("merl", []),
    ("factored", ["--outer", "2", "--inner", "2"]),
]


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


def main_() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--targets", type=int, default=20_000)
    parser.add_argument("--run", type=Path, help="an existing run file instead")
    args = parser.parse_args()
    print(describe())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        started = time.perf_counter()
        run = args.run or acquire(folder, args.targets)
        if args.run is None:
            print(f"acquired {args.targets:,} samples in {time.perf_counter() - started:.0f} s")
        print("\n| format | options | time (s) | size (MB) |")
        print("|---|---|---:|---:|")
        for name, options in FORMATS:
            out = folder / f"out.{name}"
            started = time.perf_counter()
            code = main(["export", str(run), "--format", name, "-o", str(out), "-q", *options])
            wall = time.perf_counter() - started
            assert code == 0, name
            size = sum(p.stat().st_size for p in folder.glob(f"out.{name}*"))
            shown = " ".join(options) or "—"
            print(f"| {name} | {shown} | {wall:.1f} | {size / 1e6:.1f} |", flush=True)
            for p in folder.glob(f"out.{name}*"):
                p.unlink()


if __name__ == "__main__":
    _report.run(main_, __file__, __doc__, title="Export times")
