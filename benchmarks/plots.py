"""The cost of `gonio plot`: each kind of figure of the `make demo` run (the quickstart plan,
300 targets, on the glossy metal scene), drawn by `gonio plot` in a process of its own as a
user runs it, with its CPU time, its wall time, the CPU time of the imports alone
(matplotlib and scipy with gonio's plotting), and the PNG's size in bytes and pixels.

Run: .venv/bin/python benchmarks/plots.py [--method naive] [--repeat 3]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import resource
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _report
from _machine import describe

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
GONIO = Path(sys.executable).parent / "gonio"
KINDS = ("slices", "polar", "coverage", "error")
IMPORTS = "import matplotlib.pyplot, scipy.spatial, gonio.plots.slices, gonio.plots.error"


def acquire(folder: Path) -> Path:
    """The demo's run: `make demo`'s `gonio acquire`, in this process."""
    out = folder / "quickstart.sqlite"
    args = [
        "acquire",
        str(ROOT / "configs/plans/quickstart.yaml"),
        "--scene",
        str(ROOT / "configs/scenes/glossy_metal.yaml"),
        "-o",
        str(out),
        "-q",
    ]
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(args)
    assert code == 0, f"gonio acquire exited {code}"
    return out


def child(command: list[str]) -> tuple[float, float]:
    """(CPU s, wall s) of one child process run to the end."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) in pixels, from the PNG's IHDR chunk."""
    width, height = struct.unpack(">II", path.read_bytes()[16:24])
    return width, height


def run() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--method", default="naive", help="the reconstruction drawn")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (best kept)")
    args = parser.parse_args()
    print(describe())
    imports = min(child([sys.executable, "-c", IMPORTS])[0] for _ in range(args.repeat))
    print(f"\nthe imports alone (matplotlib, scipy, gonio.plots): {imports:.2f} s of CPU\n")
    print("| kind | CPU (s) | wall (s) | PNG (KB) | pixels |")
    print("|---|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as tmp:
        run_file = acquire(Path(tmp))
        for kind in KINDS:
            out = Path(tmp) / f"{kind}.png"
            command = [str(GONIO), "plot", str(run_file), "--kind", kind, "-o", str(out)]
            if kind != "coverage":
                command += ["--method", args.method]
            cpu, wall = min(child(command) for _ in range(args.repeat))
            width, height = png_size(out)
            print(
                f"| {kind} | {cpu:.2f} | {wall:.2f} | {out.stat().st_size / 1024:.0f} | "
                f"{width} × {height} |"
            )
    print(f"\nbest of {args.repeat} runs each; the reconstruction drawn: {args.method}")


if __name__ == "__main__":
    _report.run(run, __file__, __doc__, title="The cost of gonio plot")
