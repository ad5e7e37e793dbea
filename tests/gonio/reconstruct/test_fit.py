"""Fits of simulated runs: the scene's parameters lie within the reported uncertainty,
and a wrong family shows in the reduced χ².

Coverage needs many independent noisy measurements of one scene. A run's cost is
mostly per run (~0.3 s), not per sample (~1 ms), so each scene is measured once with
`REALIZATIONS` × `SAMPLES` targets (calibrated every `SAMPLES` targets) and split
into `REALIZATIONS` interleaved subsets (every K-th sample in the measured order),
each spread over the whole domain with its own noise. The subsets share the run's
reference readings, whose error is part of each fit's uncertainty
(`gonio.analysis.shared`) but alike across subsets: their z-scores are correlated
where that error matters, so 20 subsets are fewer than 20 independent trials. The
scenes keep only noise effects: aperture integration and the footprint bias f by
design, and a fit would rightly find the biased values.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio.analysis import Calibrated, calibrate
from gonio.analysis.measured import Measured
from gonio.analysis.shared import SharedError, shared_error
from gonio.errors import GonioError
from gonio.reconstruct.fit import SIGMA_FLOOR, fit
from gonio.reconstruct.regions import NAMES
from gonio.store import Run, open_run
from tests.support.runs import plan_spec, scene_spec, simulated_run

REALIZATIONS = 20
SAMPLES = 120
NOISE = ["shot_noise", "read_noise"]
#: The glossy metal scene's own material (GGX α = 0.05, gold's complex index per channel).
GOLD = scene_spec("glossy_metal")["material"]


def long_plan(isotropic: bool = True, targets: int = REALIZATIONS * SAMPLES) -> dict[str, Any]:
    """A uniform plan on the arch rig, ordered without improvement (the order does not
    matter here), calibrated every `SAMPLES` targets with 64 exposures per reading."""
    plan = plan_spec(targets, isotropic=isotropic) | {"max_moves": 0, "kicks": 0}
    plan["acquisition"]["calibration"].update(averages=64, every_samples=SAMPLES)
    return plan


def measure(folder: Path, plan: dict[str, Any], scene: dict[str, Any]) -> Path:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return simulated_run(folder, plan, scene)


def read(path: Path) -> tuple[Measured, list[SharedError]]:
    """The run's samples and the shared calibration error of each of `realizations`,
    from one reading and one calibration of the run file."""
    run = open_run(path)
    calibrated = calibrate(run)
    return Measured.from_run(run, calibrated), shared_parts(run, calibrated)


def realizations(measured: Measured) -> list[Measured]:
    """The K interleaved subsets of a long run (module docstring)."""
    k = REALIZATIONS
    return [measured.subset(slice(j, None, k)) for j in range(k)]


def shared_parts(run: Run, calibrated: Calibrated) -> list[SharedError]:
    """The shared calibration error of each of `realizations`."""
    error = shared_error(run, calibrated)
    return [error.take(slice(j, None, REALIZATIONS)) for j in range(REALIZATIONS)]


def coverage(fits: list[Any], truth: dict[str, float]) -> dict[str, float]:
    """Per parameter, the fraction of fits whose ±2σ interval holds the truth."""
    z = np.array(
        [[(r.params()[n][0] - v) / r.params()[n][1] for n, v in truth.items()] for r in fits]
    )
    return dict(zip(truth, np.mean(np.abs(z) <= 2.0, axis=0).tolist(), strict=True))


@pytest.fixture(scope="module")
def matte(runs_dir: Path) -> tuple[Measured, list[SharedError]]:
    return read(measure(runs_dir, long_plan(), scene_spec("matte", effects=NOISE, seed=11)))


def test_matte_parameters_are_recovered_within_their_uncertainty(matte):
    measured, shared = matte
    fits = [
        fit(m, "lambert+ggx", starts=2, shared=e)
        for m, e in zip(realizations(measured), shared, strict=True)
    ]
    truth = {"lambert.albedo": 0.6, "ggx.alpha": 0.5, "ggx.f0": 0.04}
    assert min(coverage(fits, truth).values()) >= 0.9
    assert 0.7 < np.median([r.chi2_red for r in fits]) < 1.3


def test_glossy_conductor_rgb_parameters_are_recovered(runs_dir):
    """Gold seen in three bands (three runs, independent noise): α shared, the complex
    index per channel."""
    runs = [
        measure(
            runs_dir,
            long_plan(),
            scene_spec("glossy_metal", material=GOLD, effects=NOISE, band=band, seed=20 + j),
        )
        for j, band in enumerate("rgb")
    ]
    both = [read(run) for run in runs]
    parts = [realizations(measured) for measured, _ in both]
    shared = [errors for _, errors in both]
    fits = [
        fit(Measured.rgb(*rgb), "ggx:fresnel=conductor", starts=2, shared=errors)
        for rgb, errors in zip(zip(*parts, strict=True), zip(*shared, strict=True), strict=True)
    ]
    truth = {"ggx.alpha": GOLD["alpha"]}
    for j, c in enumerate("rgb"):
        truth |= {f"ggx.ior[{c}]": GOLD["ior"][j], f"ggx.k[{c}]": GOLD["k"][j]}
    assert min(coverage(fits, truth).values()) >= 0.9
    assert fits[0].model.is_rgb and len(fits[0].names) == 7


def test_anisotropic_roughness_is_recovered(runs_dir):
    run = measure(
        runs_dir, long_plan(isotropic=False), scene_spec("brushed_metal", effects=NOISE, seed=11)
    )
    spec = "ggx_anisotropic:fresnel=conductor,ior=1.2,k=7"
    measured, shared = read(run)
    parts = zip(realizations(measured), shared, strict=True)
    fits = [fit(m, spec, starts=2, shared=e) for m, e in parts]
    truth = {"ggx_anisotropic.alpha_x": 0.05, "ggx_anisotropic.alpha_y": 0.25}
    assert min(coverage(fits, truth).values()) >= 0.9


def test_a_wrong_family_shows_in_the_reduced_chi_square(runs_dir):
    material = {"name": "cook_torrance", "alpha": 0.2, "distribution": "beckmann", "f0": 0.9}
    scene = scene_spec("glossy_metal", material=material, effects=NOISE, seed=5)
    measured = Measured.from_run(measure(runs_dir, long_plan(targets=200), scene))
    right = fit(measured, "beckmann")
    assert 0.6 < right.chi2_red < 1.6
    assert right.params()["beckmann.alpha"][0] == pytest.approx(0.2, rel=1e-3)
    assert fit(measured, "phong").chi2_red > 100.0
    assert fit(measured, "ggx").chi2_red > 10.0


def test_residuals_by_region_cover_every_sample(matte):
    measured = realizations(matte[0])[0]
    result = fit(measured, "lambert+ggx", starts=1)
    assert tuple(result.regions) == NAMES
    assert sum(r.count for r in result.regions.values()) == len(measured)
    chi2 = sum(r.chi2 * r.count for r in result.regions.values())
    assert chi2 == pytest.approx(result.chi2)
    assert result.dof == len(measured) - 3


def test_a_shared_scale_moves_the_parameters_as_a_refit_would(matte):
    """A shared error's part of the uncertainty is what rescaling the data by 1 + u does."""
    measured = realizations(matte[0])[0]
    u = 1e-2
    plain = fit(measured, "lambert+ggx", starts=1)
    common = SharedError.common(len(measured), u)
    scaled = fit(measured, "lambert+ggx", starts=1, shared=common)
    refit = fit(replace(measured, f=measured.f * (1.0 + u)), "lambert+ggx", starts=1)
    expected = np.hypot(plain.stderr, refit.values - plain.values)
    np.testing.assert_allclose(scaled.stderr, expected, rtol=0.05)
    assert scaled.stderr[0] == pytest.approx(0.6 * u, rel=0.05)  # the albedo scales with f


def test_a_sample_without_uncertainty_counts_as_a_typical_one(matte):
    measured = realizations(matte[0])[0]
    honest = fit(measured, "lambert+ggx", starts=1)
    sigma, f = measured.sigma.copy(), measured.f.copy()
    sigma[0], f[0] = 0.0, f[0] + 50.0 * np.median(measured.sigma)
    tampered = fit(replace(measured, sigma=sigma, f=f), "lambert+ggx", starts=1)
    # a 50σ outlier at weight 1 of 120 moves the fit by well under its own 50σ …
    assert np.all(np.abs(tampered.values - honest.values) < 2.0 * tampered.stderr)
    sigma[0] = 1e-9 * np.median(measured.sigma)  # … and at the floor it would own it
    owned = fit(replace(measured, sigma=sigma, f=f), "lambert+ggx", starts=1)
    assert np.any(np.abs(owned.values - honest.values) > 10.0 * honest.stderr)
    assert SIGMA_FLOOR == 1e-3
    unweighted = fit(replace(measured, sigma=np.zeros_like(sigma)), "lambert+ggx", starts=1)
    np.testing.assert_allclose(unweighted.values, honest.values, rtol=2e-3)


def test_a_sum_of_two_lobes_is_fitted_jointly(runs_dir):
    """A scene whose material is a sum, fitted by the same sum (a redundant Schlick lobe
    cannot vanish: F(grazing) = 1 whatever f0, so the family must match)."""
    material = {
        "name": "sum",
        "components": [
            {"name": "lambert", "albedo": 0.3},
            {"name": "cook_torrance", "alpha": 0.08, "f0": 0.5},
            {"name": "cook_torrance", "alpha": 0.4, "f0": 0.1},
        ],
    }
    scene = scene_spec("glossy_metal", material=material, effects=NOISE, seed=6)
    measured = Measured.from_run(measure(runs_dir, long_plan(targets=200), scene))
    result = fit(measured, "lambert+ggx+ggx", starts=4)
    assert result.names[-2:] == ("ggx_2.alpha", "ggx_2.f0")
    assert 0.6 < result.chi2_red < 1.6
    truth = {"lambert.albedo": 0.3, "ggx.alpha": 0.08, "ggx.f0": 0.5, "ggx_2.alpha": 0.4}
    for name, value in truth.items():
        got, err = result.params()[name]
        assert abs(got - value) < 4.0 * err, name
    assert result.material()["name"] == "sum" and len(result.material()["components"]) == 3


def test_too_few_samples_is_one_line(matte):
    few = replace(
        matte[0], wi=matte[0].wi[:3], wo=matte[0].wo[:3], f=matte[0].f[:3], sigma=matte[0].sigma[:3]
    )
    with pytest.raises(GonioError, match="3 samples cannot fit 3 free parameters"):
        fit(few, "lambert+ggx")
