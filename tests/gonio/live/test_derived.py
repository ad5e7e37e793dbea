"""What ``gonio serve`` derives from a run's samples: the fit the residuals are taken
against and the reconstruction's slice in the plan's coordinates, recomputed every N
new samples in one worker process, never per request."""

from __future__ import annotations

import argparse
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio.acquire import control
from gonio.cli import main, serve
from gonio.live import derived
from gonio.live.model import LiveRun
from gonio.live.views import points, values
from gonio.store.read import open_run
from tests.gonio.live.conftest import forked_acquire
from tests.support.acquire import MATTE, plan_file


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("derived")
    path = folder / "run.sqlite"
    plan = plan_file(folder, target=60)
    assert main(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path), "-q"]) == 0
    return path


def test_the_fit_and_the_slice_of_a_matte_run(run: Path) -> None:
    live = LiveRun(run)
    result = derived.derive(derived.inputs_of(live, values))
    assert result.error is None and result.model is not None and result.used == 60
    assert result.chi2_red is not None and result.chi2_red < 10  # a matte scene: lambert fits
    picture = result.slice
    assert picture is not None and picture["names"] == list(live.meta["coordinate_names"][:2])
    f = np.array([np.nan if v is None else v for v in picture["f"]])
    assert len(f) == derived.RESOLUTION**2 and np.isfinite(f).sum() > 100
    shown = points(live, derived=result)
    r = np.array([np.nan if v is None else v for v in shown["residual"]])
    assert len(r) == shown["shown"] == 60 and abs(np.nanmean(r)) < 3


def test_the_server_derives_every_n_samples_not_per_request(run: Path) -> None:
    live = LiveRun(run)
    deriver = derived.Deriver(values, every=50)
    for _ in range(5):  # five requests: one job
        deriver.ask("run", live)
    give_up = time.monotonic() + 60
    while deriver.latest("run") is None:
        assert time.monotonic() < give_up, "nothing was derived"
        time.sleep(0.05)
    deriver.ask("run", live)  # no new sample since: nothing submitted
    assert deriver.generation == 1
    latest = deriver.latest("run")
    assert latest is not None and latest.measured == 60 and latest.slice is not None


def test_gonio_serve_s_defaults_are_the_deriver_s() -> None:
    parser = argparse.ArgumentParser()
    serve.add_parser(parser.add_subparsers(), "")
    args = parser.parse_args(["serve"])
    assert (args.refit_every, args.fit_model) == (derived.EVERY, derived.MODEL)


def test_the_end_of_a_run_is_derived_too(tmp_path: Path) -> None:
    plan = plan_file(tmp_path, target=60)
    path = tmp_path / "run.sqlite"
    pid = forked_acquire(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path)], 0.02)
    try:
        _until(lambda: path.exists() and len(open_run(path)) >= derived.MINIMUM)
        control.post_request(path, "pause", "the test")
        live = LiveRun(path)
        _until(lambda: live.refresh() is not None and live.state() == "paused")
        deriver = derived.Deriver(values, every=1000)
        deriver.ask("run", live)
        _until(lambda: deriver.latest("run") is not None)
        first = deriver.latest("run")
        assert first is not None and first.measured == live.measured < 60
        control.post_request(path, "resume", "the test")
        _, status = os.waitpid(pid, 0)
        pid = 0
        assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
        live.refresh()
        assert live.state() == "completed"
        deriver.ask("run", live)  # fewer than `every` new samples, but the run ended
        _until(lambda: deriver.generation == 2)
        last = deriver.latest("run")
        assert last is not None and last.measured == 60 and last.slice is not None
        deriver.ask("run", live)  # and then no more
        assert deriver.generation == 2
        deriver.close()
    finally:
        if pid:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)


def _until(check: Callable[[], bool], timeout_s: float = 60.0) -> None:
    give_up = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < give_up, "timed out"
        time.sleep(0.05)
