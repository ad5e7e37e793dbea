"""The calibration's noise model rests on the few exposures of its readings: the error of
a reading divided by its σ follows Student's t with ν = K·(n − 1) degrees of freedom (K
readings of n exposures), whose variance is ν/(ν − 2), so `noise_model` expands the
model by that factor. Readings drawn vectorized (Gaussian noise a + b·signal per
exposure, the dark's a), put through `calibration_series` as a run's calibrations: the
z-scores of the first reference rate have unit variance at every exposure count; with
the pooled model alone (the factor left out) they spread sqrt(ν/(ν − 2)): 1.29 for 5
readings of 2 exposures, 1.22 for 2 of 4, 1.13 for 3 of 4."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from scipy.stats import t as student_t

from gonio.analysis.calibrated import calibration_series, noise_model
from gonio.errors import GonioError
from gonio.planner.policies import CalibrationSpec
from gonio.radiometry.series import student_variance
from gonio.rig.model import Rig
from gonio.scene import Scene
from gonio.store.read import Event
from tests.support.calibration import scale_errors
from tests.support.runs import scene_spec

EXPOSURE = 0.05
SIGNAL, DARK = 16500.0, 17.0  # counts per exposure (the glossy scene's reference)
A, B = 0.04, 0.0017  # counts² per exposure; counts² per count of signal
RUNS = 4000


def reading(value: float, std: float | None, n: int, start: float) -> dict[str, Any]:
    return {
        "value": value,
        "n": n,
        "saturated": False,
        "std": std,
        "exposure_s": EXPOSURE,
        "started_s": start,
        "ended_s": start + 1.0,
    }


def run_events(
    ref: list[tuple[float, float | None]], dark: list[tuple[float, float | None]] | None, n: int
) -> tuple[Event, ...]:
    """One run's calibration events from its readings' (mean, spread) over n exposures."""
    out = []
    for k, (value, std) in enumerate(ref):
        data = {
            "albedo": 0.99,
            "source_kind": "collimated",
            "wi": [0.0, 0.0, 1.0],
            "wo": [-math.sqrt(0.5), 0.0, math.sqrt(0.5)],
            "reference": reading(value, std, n, 20.0 * k),
            "dark": None if dark is None else reading(*dark[k], n, 20.0 * k + 1),
        }
        out.append(Event(k, 1, "calibration", None, 20.0 * k, "", data))
    return tuple(out)


def z_scores(calibrations: int, n: int, runs: int = RUNS, seed: int = 7) -> np.ndarray:
    """Per run: the first reference rate's error over its σ."""
    rng = np.random.default_rng(seed)
    shape = (runs, calibrations, n)
    ref = rng.normal(SIGNAL + DARK, math.sqrt(A + B * SIGNAL), shape)
    dark = rng.normal(DARK, math.sqrt(A), shape)
    refs = np.stack([ref.mean(axis=2), ref.std(axis=2, ddof=1)], axis=-1).tolist()
    darks = np.stack([dark.mean(axis=2), dark.std(axis=2, ddof=1)], axis=-1).tolist()
    z = np.empty(runs)
    for r in range(runs):
        series = calibration_series(run_events(refs[r], darks[r], n))
        z[r] = (series.rate[0] - SIGNAL / EXPOSURE) / math.sqrt(series.rate_var[0])
    return z


@pytest.mark.parametrize(("calibrations", "n"), [(5, 2), (2, 4), (3, 4), (2, 16)])
def test_z_scores_have_unit_variance_at_every_exposure_count(calibrations: int, n: int) -> None:
    z = z_scores(calibrations, n)
    assert abs(float(np.mean(z))) < 0.06
    assert 0.94 <= float(np.std(z, ddof=1)) <= 1.06


def test_z_scores_follow_students_t_where_it_has_no_fourth_moment() -> None:
    """ν = 3 (3 readings of 2 exposures): the variance converges too slowly to test, the
    quantiles do not: |z| has the 90 % quantile of t₃ shrunk by sqrt(3)."""
    z = z_scores(3, 2)
    expected = float(student_t.ppf(0.95, 3)) / math.sqrt(3.0)
    assert float(np.quantile(np.abs(z), 0.9)) == pytest.approx(expected, rel=0.06)


def test_a_simulated_runs_scale_error_at_four_exposures(rigs: dict[str, Rig]) -> None:
    """The simulator's readings (shot, dark and read noise, whole ADC codes) of the default
    schedule, a calibration at the start and one at the end, of 4 exposures each (ν = 6):
    the scale's z-scores spread 1.01 over 400 seeds (1.23 without the factor)."""
    scene = Scene.model_validate(scene_spec("glossy_metal"))
    spread = scale_errors(rigs["arch"], scene, range(400), averages=4, calibrations=2).spread()
    assert 0.9 <= spread["std"] <= 1.12, spread


def test_too_few_degrees_of_freedom_give_no_sigma() -> None:
    """Two readings of 2 exposures: ν = 2, no finite variance; the plan asks for 4."""
    with pytest.raises(GonioError, match=r"2 degrees of freedom.*at least 4 exposures"):
        calibration_series(run_events([(16517.0, 5.3)] * 2, [(17.0, 0.2)] * 2, 2))
    assert calibration_series(run_events([(16517.0, 5.3)] * 3, [(17.0, 0.2)] * 3, 2)).noise_dof == 3
    with pytest.raises(ValidationError, match="greater than or equal to 4"):
        CalibrationSpec(averages=3)
    assert CalibrationSpec(averages=4).averages == 4


def test_readings_without_a_spread_count_as_exact() -> None:
    """A detector that averages on its own and gives no spread: nothing to expand."""
    series = calibration_series(run_events([(16517.0, None)] * 2, [(17.0, None)] * 2, 2))
    assert series.noise_a == series.noise_b == 0.0 and math.isinf(series.noise_dof)
    assert series.rate_var.tolist() == [0.0, 0.0]


def test_without_dark_readings_only_the_references_factor_applies() -> None:
    """A lock-in's calibrations (no dark reading): a = 0, b times ν_r/(ν_r − 2)."""
    series = calibration_series(run_events([(16500.0, 5.3), (16501.0, 5.1)], None, 4))
    pooled = np.mean([5.3**2 / 16500.0, 5.1**2 / 16501.0])
    assert series.noise_a == 0.0
    assert series.noise_b == pytest.approx(pooled * student_variance(6))


positive = st.floats(min_value=0.0, max_value=1e3)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(positive, positive, st.integers(3, 60), st.integers(3, 60)),
        min_size=1,
        max_size=6,
    ),
    st.floats(min_value=1.0, max_value=1e6),
)
def test_each_point_of_the_model_is_expanded_by_its_own_factor(
    readings: list[tuple[float, float, int, int]], signal: float
) -> None:
    """The model's variance at no signal, a, and at the references' mean signal,
    a + b·S̄, are the pooled ones times ν/(ν − 2) of the darks' and the references' ν."""
    a, b, ref_dof, dark_dof = (np.array(c, dtype=np.float64) for c in zip(*readings, strict=True))
    level = np.full(len(a), signal)
    model = noise_model(a, b, ref_dof, dark_dof, level)
    a_pooled = float(np.dot(dark_dof, a) / dark_dof.sum())
    b_pooled = float(np.dot(ref_dof, b) / ref_dof.sum())
    f_d, f_r = student_variance(dark_dof.sum()), student_variance(ref_dof.sum())
    assert model.a == pytest.approx(f_d * a_pooled, rel=1e-12, abs=1e-300)
    assert model.b_estimate == pytest.approx(b_pooled, rel=1e-12, abs=1e-300)
    at_level = max(f_r * (a_pooled + b_pooled * signal), f_d * a_pooled)
    assert model.a + model.b * signal == pytest.approx(at_level, rel=1e-9, abs=1e-300)
    if dark_dof.sum() == ref_dof.sum():
        assert model.b == pytest.approx(f_r * b_pooled, rel=1e-12, abs=1e-300)


def test_the_values_do_not_depend_on_the_noise_model() -> None:
    """Only σ is expanded: f is the same bit for bit whatever the model."""
    series = calibration_series(run_events([(16517.0, 5.3), (16520.0, 5.1)], [(17.0, 0.2)] * 2, 4))
    bare = dataclasses.replace(series, noise_a=0.0, noise_b=0.0, rate_var=series.rate_var * 0.0)
    n = 5
    args = (
        np.linspace(100.0, 9000.0, n),
        np.full(n, np.nan),
        np.ones(n, dtype=np.int64),
        np.full(n, 0.1),
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        np.tile([-math.sqrt(0.5), 0.0, math.sqrt(0.5)], (n, 1)),
        np.linspace(0.0, 20.0, n),
    )
    f, sigma = series.brdf(*args)
    f_bare, sigma_bare = bare.brdf(*args)
    assert f.tobytes() == f_bare.tobytes()
    assert np.all(sigma > sigma_bare)
