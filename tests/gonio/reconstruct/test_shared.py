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
    k = len(series.t)
    # K readings, and a last column: the dark readings' rounding (whole ADC codes here)
    assert error.weights.shape == (len(Measured.from_run(run)), k + 1)
    assert k >= 4
    readings = error.weights[:, :k]
    np.testing.assert_allclose(readings.sum(axis=1), 1.0, rtol=0, atol=1e-12)
    # the interpolation (a spline) leans on the readings around each sample most
    nearest = np.abs(readings).argmax(axis=1)
    assert np.all(np.diff(nearest) >= 0) and set(nearest) == set(range(k))
    np.testing.assert_allclose(error.relative[:k], np.sqrt(series.rate_var) / series.rate)
    assert np.all((error.relative[:k] > 0) & (error.relative[:k] < 1e-3))
    assert error.relative[k] == 1.0
    rounding = np.abs(error.weights[:, k])
    assert np.all((rounding > 0) & (rounding < 1e-3))


def test_the_interpolated_rate_is_what_the_weights_say(run):
    error = shared_error(run)
    series = calibrate(open_run(run)).series
    s = open_run(run).samples
    t = 0.5 * (s["started_s"] + s["ended_s"])
    np.testing.assert_allclose(error.weights[:, : len(series.t)] @ series.rate, series.rate_at(t))


def test_common_and_take():
    common = SharedError.common(5, 1e-4)
    assert common.weights.shape == (5, 1) and common.relative.tolist() == [1e-4]
    part = common.take(slice(1, None, 2))
    assert len(part) == 2 and part.relative is common.relative
