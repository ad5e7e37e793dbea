"""The same plan file gives the same stored plan, byte for byte, however the machine
schedules it: `gonio plan -o` in a process of its own, once left alone and once held back
(stopped for 20 ms of every 40 ms while it runs, more often than any load
would stop it, and without the busy loops' cost to the rest of the suite). The
ordering's budgets are counts (moves, kicks) drawn from the seed, and nothing of the
machine (no wall time) is stored."""

from __future__ import annotations

import hashlib
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.conftest import CONFIGS

ROOT = Path(__file__).resolve().parents[3]
#: While held back, the planning runs for `RUN_S`, then is stopped for `HELD_S` (s).
RUN_S, HELD_S = 0.02, 0.02


def plan_stored(plan: Path, out: Path, *, held: bool = False) -> tuple[bytes, int]:
    """`python -m gonio plan PLAN -o OUT` as a real process (``held``: stopped and
    continued again and again until it ends); the stored plan's bytes and the stops."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "gonio", "plan", str(plan), "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        stdin=subprocess.DEVNULL,
    )
    stops = 0
    try:
        while held and proc.poll() is None:
            time.sleep(RUN_S)
            proc.send_signal(signal.SIGSTOP)  # nothing once it has ended
            time.sleep(HELD_S)
            proc.send_signal(signal.SIGCONT)
            stops += 1
        _, err = proc.communicate(timeout=300)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, err
    return out.read_bytes(), stops


def test_the_stored_plan_is_the_same_bytes_however_the_process_is_scheduled(
    tmp_path: Path,
) -> None:
    plan = tmp_path / "plan.yaml"
    plan.write_text(
        f"name: load\nrig: {CONFIGS / 'rigs' / 'arch.yaml'}\n"
        "sampling: {strategy: sobol, target: 250, seed: 5}\nexposure: {seconds: 0.05}\n"
        "kicks: 500\n"
    )
    quiet, _ = plan_stored(plan, tmp_path / "quiet.csv")
    loaded, stops = plan_stored(plan, tmp_path / "loaded.csv", held=True)
    assert stops >= 20  # held back through its whole run (a second or more of it)
    assert hashlib.sha256(loaded).hexdigest() == hashlib.sha256(quiet).hexdigest()
    summary = next(
        json.loads(line.split(": ", 1)[1])
        for line in quiet.decode().splitlines()
        if line.startswith("# summary: ")
    )
    assert summary["stopped"] == "converged" and summary["kicks"] == 500
    assert "ordering_s" not in summary  # no wall time in a stored plan
