"""The same plan file gives the same stored plan, byte for byte, however busy the machine:
`gonio plan -o` in a process of its own, once on its own and once beside busy loops on
every core (twice over). The ordering's budgets are counts (moves, kicks) drawn from the
seed, and nothing of the machine (no wall time) is stored."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

from tests.conftest import CONFIGS

#: Busy loops beside the second planning: two per core.
HOGS = 2 * (os.cpu_count() or 2)
ROOT = Path(__file__).resolve().parents[3]


def plan_stored(plan: Path, out: Path) -> bytes:
    """`python -m gonio plan PLAN -o OUT` as a real process; the stored plan's bytes."""
    done = subprocess.run(
        [sys.executable, "-m", "gonio", "plan", str(plan), "-o", str(out)],
        capture_output=True, text=True, timeout=300, cwd=ROOT, stdin=subprocess.DEVNULL,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return out.read_bytes()


def test_the_stored_plan_is_the_same_bytes_under_heavy_load(tmp_path: Path) -> None:
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        f"name: load\nrig: {CONFIGS / 'rigs' / 'arch.yaml'}\n"
        "sampling: {strategy: sobol, target: 250, seed: 5}\nexposure: {seconds: 0.05}\n"
        "kicks: 500\n"
    )
    quiet = plan_stored(plan, tmp_path / "quiet.csv")
    hogs = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"], stdin=subprocess.DEVNULL)
        for _ in range(HOGS)
    ]
    try:
        loaded = plan_stored(plan, tmp_path / "loaded.csv")
        assert all(h.poll() is None for h in hogs)  # busy the whole time
    finally:
        for h in hogs:
            h.kill()
            h.wait()
    assert hashlib.sha256(loaded).hexdigest() == hashlib.sha256(quiet).hexdigest()
    summary = next(
        json.loads(line.split(": ", 1)[1])
        for line in quiet.decode().splitlines()
        if line.startswith("# summary: ")
    )
    assert summary["stopped"] == "converged" and summary["kicks"] == 500
    assert "ordering_s" not in summary  # no wall time in a stored plan
