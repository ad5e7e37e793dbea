"""`gonio watch` as a person on SSH uses it: through a pseudo-terminal (pexpect) it
redraws a run being acquired in place and quits on ``q`` with the run going on; piped,
it prints plain lines and exits once nobody acquires the run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pexpect
import pytest

from gonio.acquire import control
from gonio.analysis import calibrate
from gonio.live.model import LiveRun
from gonio.live.terminal import last_samples
from gonio.store.read import open_run
from tests.gonio.live.conftest import ROOT, forked_acquire
from tests.support.acquire import MATTE, plan_file


def _wait_for(path: Path, samples: int) -> None:
    give_up = time.monotonic() + 30
    while not (path.exists() and len(open_run(path)) >= samples):
        assert time.monotonic() < give_up, "the run did not start"
        time.sleep(0.05)


def test_watch_in_a_terminal_and_piped(tmp_path: Path) -> None:
    plan = plan_file(tmp_path, target=60)
    path = tmp_path / "run.sqlite"
    pid = forked_acquire(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path)], 0.02)
    try:
        _wait_for(path, 2)
        control.post_request(path, "pause", "test")  # held while the view starts
        env = {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "100", "LINES": "30"}
        term = pexpect.spawn(
            sys.executable,
            ["-m", "gonio", "watch", str(path), "--every", "0.3"],
            env=env,
            dimensions=(30, 100),
            timeout=30,
            encoding="utf-8",
        )
        term.expect(r"\[paused\]")
        term.expect(r"samples (\d+) of 60")
        first = int(term.match.group(1))
        control.post_request(path, "resume", "test")
        term.expect(r"\x1b\[H\x1b\[2J")  # redrawn in place
        term.expect(r"samples (\d+) of 60")
        while int(term.match.group(1)) == first:
            term.expect(r"samples (\d+) of 60")
        # the last samples by their angles (degrees) and calibrated value, not raw counts
        term.expect(r"last samples \(θi φi θo φo in degrees; f ± 1σ in sr⁻¹\):")
        term.expect(r"target \d+: +[\d.]+ +[\d.]+ +[\d.]+ +[\d.]+  f [\d.e+-]+ ± [\d.e+-]+")
        term.expect(r"reason=request")  # the pause among the events
        term.expect("q or Ctrl-C: quit")
        term.send("q")
        term.expect(pexpect.EOF)
        term.close()
        assert term.exitstatus == 0
        assert "\x1b[?25h" in (term.before or "")  # the cursor shown again
        piped = subprocess.run(
            [sys.executable, "-m", "gonio", "watch", str(path), "--every", "0.2"],
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        )
        lines = piped.stdout.splitlines()
        assert lines[-1].startswith("run.sqlite: completed, 60/60 samples (100.0 %)")
        assert "\x1b" not in piped.stdout
        _, status = os.waitpid(pid, 0)
        pid = 0
        assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
    finally:
        if pid:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
    run = open_run(path)
    assert run.complete  # quitting the view left the run alone
    # The watch's last samples are the analysis's calibrated ones (an independent path).
    calibrated = calibrate(run)
    wi, wo = run.directions()
    shown = last_samples(LiveRun(path))
    assert len(shown) == 4
    for line, k in zip(shown[1:], range(len(run) - 3, len(run)), strict=True):
        target, rest = line.split(":", 1)
        assert int(target.split()[-1]) == int(run.samples["target"][k])
        angles = [float(v) for v in rest.split("f")[0].split()]
        expected = [
            np.degrees(np.arccos(wi[k, 2])),
            np.degrees(np.arctan2(wi[k, 1], wi[k, 0])) % 360,
            np.degrees(np.arccos(wo[k, 2])),
            np.degrees(np.arctan2(wo[k, 1], wo[k, 0])) % 360,
        ]
        assert angles == pytest.approx(expected, abs=0.051)
        f, sigma = (float(v) for v in rest.split(" f ")[1].split(" (t")[0].split(" ± "))
        assert f == pytest.approx(calibrated.brdf[k], rel=1e-3)
        assert sigma == pytest.approx(calibrated.sigma[k], rel=1e-2)
