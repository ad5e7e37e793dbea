"""The whole `make test` from a clean clone, as CI runs it: `git clone` of the committed
tree into a temporary folder, then `CI=true make test` there with no standard input
(a new virtual environment and the install of the test and docs extras by uv, itself
installed by pip; then side by side ruff and the import contracts, the documentation
site's strict build, the browser's install where it is missing, and the warm-up: the
planner's numba kernels compiled into their cache and the suite collected once, which
writes the byte code of what the tests import and of the test modules as pytest
rewrites their asserts; then the test suite on three workers, the site's browser tests
opening the site just built, with mypy beside it at nice 10). Prints the wall time of
each stage and the suite's own summary line; the budget is 4 minutes on the 2-core
machine, install included.

Run: .venv/bin/python benchmarks/make_test.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _report
from _machine import describe

ROOT = Path(__file__).resolve().parents[1]
#: The stages `make test` runs, by the first line each prints.
STAGES = (
    ("install", re.compile(r"pip .* install")),
    ("checks", re.compile(r"^checks: ")),
    ("suite", re.compile(r"^the suite, ")),
)
BUDGET_S = 240.0


def one_run() -> tuple[dict[str, float], float, str]:
    """The seconds each stage took, the total, and pytest's summary line."""
    with tempfile.TemporaryDirectory(prefix="gonio-make-test-") as tmp:
        clone = Path(tmp) / "gonio"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        env = {**os.environ, "CI": "true"}
        env.pop("VIRTUAL_ENV", None)
        start = time.perf_counter()
        marks: dict[str, float] = {}
        summary = ""
        tail: list[str] = []
        with subprocess.Popen(
            ["make", "test"],
            cwd=clone,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        ) as proc:
            assert proc.stdout is not None
            for line in proc.stdout:
                tail = [*tail[-29:], line]
                for name, pattern in STAGES:
                    if name not in marks and pattern.search(line):
                        marks[name] = time.perf_counter() - start
                if re.search(r"\d+ passed", line):
                    summary = line.strip()
        total = time.perf_counter() - start
        if proc.returncode != 0:
            sys.stderr.writelines(tail)
            raise SystemExit(f"make test failed in the clean clone (exit {proc.returncode})")
    starts = [marks.get(name, 0.0) for name, _ in STAGES] + [total]
    stages = {name: starts[i + 1] - starts[i] for i, (name, _) in enumerate(STAGES)}
    return stages, total, summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="clean clones to time (1)")
    args = parser.parse_args()
    print(describe())
    print()
    print("| run | install s | checks s | suite and mypy s | total s | within 4 min |")
    print("|---:|---:|---:|---:|---:|---|")
    summaries = []
    for n in range(1, args.repeat + 1):
        stages, total, summary = one_run()
        cells = " | ".join(f"{stages[name]:.0f}" for name, _ in STAGES)
        ok = "yes" if total <= BUDGET_S else "no"
        print(f"| {n} | {cells} | {total:.0f} | {ok} |", flush=True)
        summaries.append(summary)
    print()
    for n, summary in enumerate(summaries, 1):
        print(f"run {n}, the suite: {summary}")


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="make test from a clean clone")
