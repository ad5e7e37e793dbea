"""`reconstruct` end to end: accuracy, seams, RGB, anisotropy, the support mask and its
fills, uncertainty, shapes, and one-line errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from gonio import brdf, params
from gonio.analysis.measured import Measured
from gonio.brdf.base import BRDF
from gonio.errors import GonioError
from gonio.reconstruct import METHODS, Reconstruction, reconstruct
from gonio.reconstruct.coordinates import Space
from gonio.rig.model import Rig
from studies.reconstruct.synthetic import placed, synthesize


def _relative(r: Reconstruction, truth: BRDF, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    f, _, ok = r.evaluate(wi, wo)
    assert ok.mean() > 0.95
    t = truth.eval(wi, wo)[ok]
    return np.asarray(np.abs(f[ok] - t) / t)


@pytest.fixture(scope="module")
def queries(arch: Rig) -> tuple[np.ndarray, np.ndarray]:
    return placed(arch, "hybrid", True, 3000, seed=9)


@pytest.mark.parametrize("method", ["linear", "rbf"])
def test_a_smooth_brdf_is_reconstructed_closely(
    method: str, matte_iso: Measured, matte: BRDF, queries: tuple[np.ndarray, np.ndarray]
) -> None:
    rel = _relative(reconstruct(matte_iso, method=method), matte, *queries)
    assert np.median(rel) < 1e-3
    assert np.percentile(rel, 95) < 2e-2


def test_a_sample_is_reproduced_exactly_by_every_interpolating_method(
    matte_iso: Measured, matte: BRDF
) -> None:
    for method in ("linear", "rbf"):
        f = reconstruct(matte_iso, method=method).eval(matte_iso.wi[:200], matte_iso.wo[:200])
        # To the 1e-6 displacement of the seam copies a sample near a seam is blended with.
        np.testing.assert_allclose(f, matte_iso.f[:200], rtol=1e-6, equal_nan=False)


def test_model_plus_residual_with_the_true_model_returns_the_model(
    matte_iso: Measured, matte: BRDF, queries: tuple[np.ndarray, np.ndarray]
) -> None:
    r = reconstruct(matte_iso, method="model+residual", model=matte)
    f, _, ok = r.evaluate(*queries)
    np.testing.assert_allclose(f[ok], matte.eval(*queries)[ok], rtol=1e-12)
    assert r.transform == "ratio"


def test_model_plus_residual_corrects_a_wrong_model(
    matte_iso: Measured, matte: BRDF, queries: tuple[np.ndarray, np.ndarray]
) -> None:
    wrong = brdf.create(
        "cook_torrance", alpha=0.3, distribution="ggx", fresnel="schlick", f0=0.04, kd=0.4
    )
    assert np.median(np.abs(wrong.eval(*queries) / matte.eval(*queries) - 1.0)) > 0.2
    rel = _relative(reconstruct(matte_iso, method="model+residual", model=wrong), matte, *queries)
    assert np.median(rel) < 2e-3


@pytest.mark.parametrize(
    ("name", "isotropic"),
    [("hybrid", True), ("rusinkiewicz", True), ("spherical", True), ("hybrid", False)],
)
def test_values_either_side_of_an_azimuth_seam_agree(
    arch: Rig, brushed: BRDF, name: str, isotropic: bool
) -> None:
    r = (
        _aniso(arch, brushed)
        if not isotropic
        else reconstruct(synthesize(brushed.eval, arch, name, isotropic, 1500))
    )
    space = Space(name, isotropic)
    p = params.get(name)
    valid, inverse = (p.valid_iso, p.inverse_iso) if isotropic else (p.valid, p.inverse)
    rng = np.random.default_rng(4)
    for axis, _ in space.periods:
        coords = rng.uniform(0.2, 0.6, (600, space.dims)) * space.extent
        sides = []
        for side in (1e-9, 1.0 - 1e-9):  # just above 0 and just below the period
            c = coords.copy()
            c[:, axis] = side * space.extent[axis]
            sides.append(c)
        keep = valid(sides[0]) & valid(sides[1])
        (a, sa, oka), (b, sb, okb) = (r.evaluate(*inverse(c[keep])) for c in sides)
        both = oka & okb
        assert both.sum() > 50
        np.testing.assert_allclose(a[both], b[both], rtol=1e-6)
        np.testing.assert_allclose(sa[both], sb[both], rtol=1e-6)


def _aniso(arch: Rig, brushed: BRDF) -> Reconstruction:
    """The anisotropic material reconstructed from 1 500 hybrid samples (built once)."""
    if "aniso" not in _ANISO:
        _ANISO["aniso"] = reconstruct(synthesize(brushed.eval, arch, "hybrid", False, 1500))
    return _ANISO["aniso"]


_ANISO: dict[str, Reconstruction] = {}


def test_an_rgb_measurement_gives_three_channels(
    arch: Rig, queries: tuple[np.ndarray, np.ndarray]
) -> None:
    colour = brdf.create(
        "cook_torrance",
        alpha=0.5,
        distribution="ggx",
        fresnel="schlick",
        f0=0.04,
        kd=(0.6, 0.3, 0.1),
    )
    r = reconstruct(synthesize(colour.eval, arch, "hybrid", True, 1500))
    assert r.is_rgb
    f = r.eval(*queries)
    assert f.shape == (len(queries[0]), 3)
    rel = np.abs(f - colour.eval(*queries)) / colour.eval(*queries)
    assert np.nanmedian(rel, axis=0).max() < 1e-3
    assert r.uncertainty(queries[0][:5], queries[1][:5]).shape == (5, 3)


def test_an_anisotropic_run_keeps_the_azimuth(arch: Rig, brushed: BRDF) -> None:
    r = _aniso(arch, brushed)
    wi, wo = placed(arch, "hybrid", False, 1000, seed=9)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90° about n
    f, _, ok = r.evaluate(wi, wo)
    g, _, ok2 = r.evaluate(wi @ turn.T, wo @ turn.T)
    both = ok & ok2
    truth, turned = brushed.eval(wi, wo)[both], brushed.eval(wi @ turn.T, wo @ turn.T)[both]
    # A quarter turn changes the material's value far more than the reconstruction errs
    # (1 500 samples in four coordinates: about 6 per axis).
    change = np.median(np.abs(truth - turned) / truth)
    assert change > 0.3
    assert np.median(np.abs(f[both] - truth) / truth) < 0.3 * change
    assert np.median(np.abs(g[both] - turned) / truth) < 0.3 * change


def test_beyond_theta_max_and_in_the_blind_spot_is_not_supported(
    matte_iso: Measured,
) -> None:
    r = reconstruct(matte_iso)
    steep = np.radians(85.0)  # the arch's θmax is 80°
    wi = np.array([[np.sin(steep), 0.0, np.cos(steep)], [0.6, 0.0, 0.8], [0.6, 0.0, 0.8]])
    wo = np.array([[-0.6, 0.0, 0.8], [0.6, 0.0, 0.8], [-0.6, 0.0, 0.8]])  # last: measurable
    f, sigma, ok = r.evaluate(wi, wo)
    assert ok.tolist() == [False, False, True]
    assert np.isnan(f[:2]).all()
    assert np.isnan(sigma[:2]).all()
    assert np.isfinite(f[2])


def test_far_from_every_sample_is_not_supported_unless_filled(
    matte_iso: Measured, matte: BRDF
) -> None:
    space = Space("hybrid", True)
    x = space.scaled(matte_iso.wi, matte_iso.wo)
    centre = np.array([0.35, 0.45, 0.5])
    keep = np.linalg.norm(x - centre, axis=1) > 0.3
    holed = matte_iso.subset(keep)
    wi, wo = params.get("hybrid").inverse_iso(centre * space.extent)
    assert not reconstruct(holed).supported(wi, wo)
    assert np.isnan(reconstruct(holed).eval(wi, wo))
    nearest = reconstruct(holed, extrapolate="nearest").eval(wi, wo)
    # The fill: log(1 + f) of the 8 nearest samples, weighted by 1/distance².
    distance, index = cKDTree(space.scaled(holed.wi, holed.wo)).query(centre, k=8)
    weight = 1.0 / distance**2
    expected = np.expm1(np.sum(weight * np.log1p(holed.f[index])) / np.sum(weight))
    assert float(nearest) == pytest.approx(expected, rel=1e-12)
    modelled = reconstruct(holed, extrapolate="model", model=matte).eval(wi, wo)
    assert modelled == pytest.approx(float(matte.eval(wi, wo)), rel=1e-12)
    assert np.isnan(reconstruct(holed, extrapolate="model", model=matte).uncertainty(wi, wo))


def test_the_uncertainty_scales_with_the_samples_sigma(
    matte_iso: Measured, queries: tuple[np.ndarray, np.ndarray]
) -> None:
    once = reconstruct(matte_iso).uncertainty(*queries)
    doubled = dataclasses.replace(matte_iso, sigma=2.0 * matte_iso.sigma)
    twice = reconstruct(doubled).uncertainty(*queries)
    ok = np.isfinite(once)
    np.testing.assert_allclose(twice[ok], 2.0 * once[ok], rtol=1e-9)
    f = reconstruct(matte_iso).eval(*queries)
    # 1 % at every sample: about 1 % of the value between them.
    assert np.median(once[ok] / f[ok]) == pytest.approx(0.01, rel=0.05)


def test_a_real_simulated_run_agrees_with_its_scene(simulated_matte: Measured) -> None:
    truth = simulated_matte.scene_truth()
    r = reconstruct(simulated_matte)
    wi, wo = placed(simulated_matte.rig, "hybrid", True, 3000, seed=9)
    f, _, ok = r.evaluate(wi, wo)
    assert ok.mean() > 0.9
    rel = np.abs(f[ok] - truth(wi, wo)[ok]) / truth(wi, wo)[ok]
    # 300 samples of a smooth material, through the detector's aperture and footprint
    # (measured: median 5e-4, 95th percentile 1.9e-2).
    assert np.median(rel) < 2e-3
    assert np.percentile(rel, 95) < 4e-2


@settings(max_examples=25)
@given(
    lead_i=st.lists(st.integers(1, 3), max_size=2),
    below=st.booleans(),
)
def test_shapes_broadcast_like_an_analytic_model(
    matte_iso: Measured, lead_i: list[int], below: bool
) -> None:
    r = _shared_reconstruction(matte_iso)
    wi = np.broadcast_to(np.array([0.3, 0.1, np.sqrt(0.9)]), (*lead_i, 3))
    wo = np.array([-0.4, 0.0, -np.sqrt(0.84) if below else np.sqrt(0.84)])
    f, sigma, ok = r.evaluate(wi, wo)
    assert f.shape == sigma.shape == ok.shape == tuple(lead_i)
    if below:
        assert (f == 0).all()
        assert (sigma == 0).all()
        assert not ok.any()
    else:
        assert np.isfinite(f).all()
        assert np.allclose(f, f.flat[0])


_CACHE: dict[int, Reconstruction] = {}


def _shared_reconstruction(measured: Measured) -> Reconstruction:
    if id(measured) not in _CACHE:
        _CACHE[id(measured)] = reconstruct(measured)
    return _CACHE[id(measured)]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "cubic"}, "unknown reconstruction method 'cubic'"),
        ({"parametrization": "polar"}, "unknown parametrization 'polar'"),
        ({"extrapolate": "linear"}, "unknown extrapolation 'linear'"),
        ({"method": "model+residual"}, "needs a model"),
        ({"extrapolate": "model"}, "needs a model"),
        ({"transform": "sqrt"}, "unknown transform 'sqrt'"),
        ({"max_distance": -1.0}, "max_distance"),
    ],
)
def test_bad_options_are_one_line_errors(
    matte_iso: Measured, kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(GonioError, match=message) as err:
        reconstruct(matte_iso, **kwargs)  # type: ignore[arg-type]
    assert "\n" not in str(err.value)


def test_every_method_is_named_and_reported(matte_iso: Measured, matte: BRDF) -> None:
    assert METHODS == ("linear", "rbf", "grid", "lines", "model+residual")
    r = reconstruct(matte_iso, method="rbf", parametrization="spherical")
    assert (r.method, r.parametrization, r.isotropic, r.transform) == (
        "rbf",
        "spherical",
        True,
        "log",
    )
