"""The error a run's samples share through its reference readings."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest

from gonio.analysis.calibrated import calibrate
from gonio.analysis.measured import Measured
from gonio.analysis.shared import SharedError, shared_error
from gonio.store.read import open_run
from tests.support.runs import plan_spec, scene_spec, simulated_run


@pytest.fixture(scope="module")
def run(runs_dir: Path):
    plan = plan_spec(60) | {"max_moves": 0, "kicks": 0}
    plan["acquisition"]["calibration"]["every_samples"] = 20
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return simulated_run(runs_dir, plan, scene_spec("matte", noise=True, seed=4))


def test_weights_interpolate_the_readings_in_time(run):
    error = shared_error(run)
    series = calibrate(open_run(run)).series
    assert error.weights.shape == (len(Measured.from_run(run)), len(series.t))
    assert len(series.t) >= 4
    np.testing.assert_allclose(error.weights.sum(axis=1), 1.0, rtol=0, atol=1e-12)
    assert np.all(error.weights >= 0.0)
    # linear interpolation: at most two readings per sample, and each reading is used
    assert np.all((error.weights > 0).sum(axis=1) <= 2)
    assert np.all(error.weights.max(axis=0) > 0.0)
    np.testing.assert_allclose(error.relative, np.sqrt(series.rate_var) / series.rate)
    assert np.all((error.relative > 0) & (error.relative < 1e-3))


def test_the_interpolated_rate_is_what_the_weights_say(run):
    error = shared_error(run)
    series = calibrate(open_run(run)).series
    s = open_run(run).samples
    t = 0.5 * (s["started_s"] + s["ended_s"])
    np.testing.assert_allclose(error.weights @ series.rate, np.interp(t, series.t, series.rate))


def test_common_and_take():
    common = SharedError.common(5, 1e-4)
    assert common.weights.shape == (5, 1) and common.relative.tolist() == [1e-4]
    part = common.take(slice(1, None, 2))
    assert len(part) == 2 and part.relative is common.relative
