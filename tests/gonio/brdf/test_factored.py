"""The factored BRDF read from its files: eval, the sampler's density and its draws."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import gonio.brdf as brdf
from gonio.brdf import factored_file as ff
from gonio.brdf.factored import Factored
from gonio.brdf.quadrature import directional_albedo
from gonio.config import ConfigError
from gonio.errors import DomainError
from gonio.export.factored import Resolution, export, table
from gonio.params.cases import direction

RES = Resolution(theta_out=8, phi_out=16, theta_p=16, phi_p=32, z=256)
GLOSSY = {"alpha": 0.2, "fresnel": "schlick", "f0": 0.9, "kd": 0.2}
GOLD = {
    "alpha": 0.3,
    "fresnel": "conductor",
    "ior": (0.18, 0.42, 1.37),
    "k": (3.42, 2.35, 1.77),
}
VIEWS = (0.1, 0.7, 1.25)  # θo of the views tested, radians (φo = 0.3)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    folder = tmp_path_factory.mktemp("factored")
    out = {}
    for name, params, j, k in (("glossy", GLOSSY, 3, 2), ("gold", GOLD, 2, 2)):
        path = folder / f"{name}.txt"
        export(brdf.create("cook_torrance", **params), path, j, k, RES)
        out[name] = str(path)
    return out


@pytest.fixture(scope="module")
def glossy(files: dict[str, str]) -> Factored:
    model = brdf.create("factored", path=files["glossy"])
    assert isinstance(model, Factored)
    return model


def _view(theta: float) -> np.ndarray:
    return direction(theta, 0.3)


def test_create_reads_both_files_and_keeps_its_path(files, glossy):
    assert glossy.name == "factored"
    assert glossy.params == {"path": files["glossy"]}
    assert not glossy.is_rgb
    assert not glossy.isotropic
    assert brdf.create("factored", path=files["gold"]).is_rgb
    with pytest.raises(DomainError, match="path"):
        brdf.create("factored")


def test_eval_is_the_outer_factorization_over_cos_theta_i(glossy):
    """At the bin centres f cos θi is Σⱼ Fⱼ Gⱼ of the table, bin by bin."""
    t = glossy.tables
    a, b, c, d = 3, 5, 2, 7  # θo, φo, θh, φh bins
    wo = direction((a + 0.5) * np.pi / 2 / 8, (b + 0.5) * 2 * np.pi / 16)
    h = direction((c + 0.5) * np.pi / 2 / 16, (d + 0.5) * 2 * np.pi / 32)
    wi = 2.0 * (wo @ h) * h - wo
    assert wi[2] > 0.0
    expected = np.sum(t.F[:, a, b] * t.G[:, c, d]) / wi[2]
    np.testing.assert_allclose(glossy.eval(wi, wo), expected, rtol=1e-12)


def test_eval_approximates_the_model_it_was_made_from(glossy):
    model = brdf.create("cook_torrance", **GLOSSY)
    y = table(model, RES)
    wo = direction(
        ((np.arange(8) + 0.5) * np.pi / 16)[:, None], ((np.arange(16) + 0.5) * np.pi / 8)
    )
    h = direction(
        ((np.arange(16) + 0.5) * np.pi / 32)[:, None], ((np.arange(32) + 0.5) * np.pi / 16)
    )
    wo, h = wo[:, :, None, None], h[None, None]
    wi = 2.0 * np.sum(wo * h, axis=-1, keepdims=True) * h - wo
    lit = wi[..., 2] > 0.0
    got = np.zeros(lit.shape)
    wo_b = np.broadcast_to(wo, wi.shape)
    got[lit] = glossy.eval(wi[lit], wo_b[lit]) * wi[lit][:, 2]
    error = np.linalg.norm(got - y) / np.linalg.norm(y)
    assert 0.0 < error < 0.2  # J = 3 on a coarse grid (docs/reference/formats_factored.md)


def test_eval_of_an_rgb_file_scales_the_intensity_by_the_colour_factors(files):
    gold = brdf.create("factored", path=files["gold"])
    wi, wo = direction(0.5, 3.4), direction(0.5, 0.3)  # near the mirror direction
    rgb = gold.eval(wi, wo)
    truth = brdf.create("cook_torrance", **GOLD).eval(wi, wo)
    assert rgb.shape == (3,)
    assert rgb[0] > rgb[1] > rgb[2]  # gold: red above green above blue
    np.testing.assert_allclose(rgb, truth, rtol=0.35)


def test_eval_is_zero_on_the_horizon_and_below(glossy):
    wo = _view(0.4)
    assert glossy.eval(np.array([np.cos(1.0), np.sin(1.0), 0.0]), wo) == 0.0
    elevation = np.logspace(-12, -6, 7)
    near = glossy.eval(direction(np.pi / 2 - elevation, 3.4), wo)
    assert np.all(np.isfinite(near))
    assert np.all(near * np.sin(elevation) < 1e-4)  # f cos θi → 0: no 1/cos θi spike
    assert glossy.eval(np.array([0.0, 0.6, -0.8]), wo) == 0.0


def _midpoint_integral(func, n: int = 300, sign: float = 1.0) -> float:
    """∫ func(w) dω over the upper (sign 1) or lower (−1) hemisphere: midpoint rule in
    (cos θ, φ) on n × 2n cells (a tensor Gauss rule does worse on the density's jumps)."""
    mu = (np.arange(n) + 0.5) / n
    phi = (np.arange(2 * n) + 0.5) * np.pi / n
    s = np.sqrt(1.0 - mu * mu)[:, None]
    grid = np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), sign * mu[:, None]), -1)
    return float(func(grid.reshape(-1, 3)).sum() * (1.0 / n) * (np.pi / n))


@pytest.mark.parametrize("theta_o", VIEWS)
def test_density_integrates_to_one(glossy, theta_o):
    """pdf(wo, wi) (the 1/(4 wi·ĥ) Jacobian included) integrates to 1 over the sphere of
    wi; over the upper hemisphere to the share of draws that land there."""
    wo = _view(theta_o)
    upper = _midpoint_integral(lambda w: glossy.pdf(wo, w))
    lower = _midpoint_integral(lambda w: glossy.pdf(wo, w), sign=-1.0)
    assert abs(upper + lower - 1.0) < 1e-3
    n = 400_000
    wi, _ = glossy.sample(np.broadcast_to(wo, (n, 3)), np.random.default_rng(3).random((n, 3)))
    share = np.mean(wi[:, 2] >= 0.0)
    assert abs(upper - share) < 4.0 * np.sqrt(share * (1.0 - share) / n) + 1e-3
    assert 0.5 < upper < 0.999  # the half-angle draws do leak below the horizon


def _chi2_counts(wo, wi, pdf_of, n_mu=10, n_phi=20, sub=24):
    """Observed and expected counts in (cos θi, φi) cells of the upper hemisphere and one
    cell for the draws below the horizon."""
    n = len(wi)
    up = wi[:, 2] >= 0.0
    phi = np.arctan2(wi[up, 1], wi[up, 0]) % (2 * np.pi)
    mu_bin = np.minimum((wi[up, 2] * n_mu).astype(int), n_mu - 1)
    phi_bin = np.minimum((phi * n_phi / (2 * np.pi)).astype(int), n_phi - 1)
    observed = np.bincount(mu_bin * n_phi + phi_bin, minlength=n_mu * n_phi)
    mu = (np.arange(n_mu * sub) + 0.5) / (n_mu * sub)
    ph = (np.arange(n_phi * sub) + 0.5) * 2 * np.pi / (n_phi * sub)
    s = np.sqrt(1.0 - mu * mu)[:, None]
    grid = np.stack(np.broadcast_arrays(s * np.cos(ph), s * np.sin(ph), mu[:, None]), -1)
    cell = (1.0 / (n_mu * sub)) * (2 * np.pi / (n_phi * sub))  # dω = dμ dφ
    p = pdf_of(wo, grid.reshape(-1, 3)).reshape(n_mu, sub, n_phi, sub) * cell
    expected = p.sum(axis=(1, 3)).ravel() * n
    observed = np.append(observed, n - up.sum())
    expected = np.append(expected, max(n - expected.sum(), 0.0))
    keep = expected > 5.0
    return observed[keep], expected[keep] * observed[keep].sum() / expected[keep].sum()


@pytest.mark.parametrize("theta_o", VIEWS)
def test_draws_follow_the_density(glossy, theta_o):
    wo = _view(theta_o)
    n = 200_000
    u = np.random.default_rng(11).random((n, 3))
    wi, pdf = glossy.sample(np.broadcast_to(wo, (n, 3)), u)
    np.testing.assert_allclose(pdf, glossy.pdf(wo, wi), rtol=1e-4)  # wo·ĥ recomputed
    observed, expected = _chi2_counts(wo, wi, glossy.pdf)
    assert stats.chisquare(observed, expected).pvalue > 1e-3

    def without_jacobian(wo_, wi_):  # the density the seed's 1/(4 wi·ĥ) corrects
        h = wi_ + wo_
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        return glossy.pdf(wo_, wi_) * 4.0 * np.abs(h @ wo_)

    observed, expected = _chi2_counts(wo, wi, without_jacobian)
    assert stats.chisquare(observed, expected).pvalue < 1e-6


@pytest.mark.parametrize("theta_o", [0.2, 1.0])
def test_sampled_albedo_matches_quadrature_with_less_variance_than_cosine(glossy, theta_o):
    model = brdf.create("cook_torrance", **GLOSSY)
    wo = _view(theta_o)
    truth = float(directional_albedo(model, theta_o, 0.3))
    n = 100_000
    rng = np.random.default_rng(5)
    wi, pdf = glossy.sample(np.broadcast_to(wo, (n, 3)), rng.random((n, 3)))
    lit = (wi[:, 2] > 0.0) & (pdf > 0.0)
    x = np.zeros(n)
    x[lit] = model.eval(wi[lit], wo) * wi[lit, 2] / pdf[lit]
    r = rng.random((n, 2))
    s = np.sqrt(r[:, 0])
    cos_dirs = np.stack([s * np.cos(2 * np.pi * r[:, 1]), s * np.sin(2 * np.pi * r[:, 1])], -1)
    cos_dirs = np.concatenate([cos_dirs, np.sqrt(1.0 - r[:, :1])], axis=-1)
    y = model.eval(cos_dirs, wo) * np.pi  # f cos θi / (cos θi / π)
    assert abs(x.mean() - truth) < 4.0 * x.std() / np.sqrt(n)
    assert abs(y.mean() - truth) < 4.0 * y.std() / np.sqrt(n)
    assert x.var() < 0.5 * y.var()


def test_sample_and_pdf_broadcast_and_check_their_inputs(glossy):
    wi, pdf = glossy.sample(_view(0.5), np.full((4, 5, 3), 0.25))
    assert wi.shape == (4, 5, 3)
    assert pdf.shape == (4, 5)
    assert glossy.pdf(_view(0.5), wi).shape == (4, 5)
    with pytest.raises(DomainError, match=r"\[0, 1\)"):
        glossy.sample(_view(0.5), [0.2, 1.0, 0.3])
    with pytest.raises(DomainError, match="wo"):
        glossy.sample([0.0, 0.0, -1.0], [0.2, 0.5, 0.3])
    assert glossy.pdf(_view(0.5), -_view(0.5)) == 0.0  # wi = −wo: no halfway vector


def test_a_file_without_energy_samples_uniform_terms_without_warnings(tmp_path):
    export(brdf.create("lambert", albedo=0.0), tmp_path / "black.txt", 1, 1, RES)
    black = brdf.create("factored", path=str(tmp_path / "black.txt"))
    wi, pdf = black.sample(_view(0.3), np.random.default_rng(0).random((100, 3)))
    assert np.all(np.isfinite(wi))
    assert np.all(pdf >= 0.0)
    assert np.all(black.eval(wi[wi[:, 2] > 0], _view(0.3)) == 0.0)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda s: s.replace("param: halfangle", "param: spherical"), r":2: param: expected"),
        (lambda s: s.replace("theta_out_count: 8", "theta_out_count: eight"), "positive integer"),
        (lambda s: s.replace("F_0\n", "F_1\n", 1), "expected 'F_0'"),
        (lambda s: s.replace("\nEOF\n", "\n"), "ends early; expected EOF"),
        (lambda s: s.replace("INTENSITY DATA\n", "INTENSITY DATA\nF_0\n1 2 x\n", 1), "numbers"),
        # Sizes no file holds: refused before anything is allocated (not 6.94 EiB).
        (
            lambda s: s.replace("theta_out_count: 8", "theta_out_count: 1000000000").replace(
                "phi_out_count: 16", "phi_out_count: 1000000000"
            ),
            "the header states .* values; the file holds at most",
        ),
        (lambda s: s.replace("theta_out_count: 8", "theta_out_count: " + "9" * 5000), "positive"),
    ],
)
def test_a_malformed_factor_file_is_one_line_naming_file_and_line(files, tmp_path, edit, message):
    bad = tmp_path / "bad.txt"
    source = Path(files["glossy"]).read_text()
    bad.write_text(edit(source))
    (tmp_path / ("bad.txt" + ff.CDF_SUFFIX)).write_text(
        Path(files["glossy"] + ff.CDF_SUFFIX).read_text()
    )
    with pytest.raises(ConfigError, match=message) as err:
        brdf.create("factored", path=str(bad))
    assert str(bad) in str(err.value)
    assert "\n" not in str(err.value)


def test_a_missing_or_broken_cdf_file_is_refused(files, tmp_path):
    path = tmp_path / "f.txt"
    path.write_text(Path(files["glossy"]).read_text())
    with pytest.raises(ConfigError, match=r"f\.txt\.cdf: cannot read"):
        brdf.create("factored", path=str(path))
    cdf = Path(files["glossy"] + ff.CDF_SUFFIX).read_text().splitlines()
    cdf[3] = " ".join(["0.5"] * 32)  # P(phi_p|term 0) not ending at 1
    (tmp_path / "f.txt.cdf").write_text("\n".join(cdf) + "\n")
    with pytest.raises(ConfigError, match="non-decreasing CDF ending at 1"):
        brdf.create("factored", path=str(path))


def test_a_factored_file_is_a_scene_material(files, tmp_path_factory):
    """A simulated run of a scene whose material is the factored file measures it."""
    from gonio.analysis.measured import Measured
    from tests.support.runs import plan_spec, scene_spec, simulated_run

    material = {"name": "factored", "path": files["glossy"]}
    scene = scene_spec(material=material, noise=False)
    run = simulated_run(tmp_path_factory.mktemp("run"), plan_spec(100), scene)
    measured = Measured.from_run(str(run))
    truth = brdf.create("factored", path=files["glossy"]).eval(measured.wi, measured.wo)
    np.testing.assert_array_equal(measured.scene_truth()(measured.wi, measured.wo), truth)
    lit = truth > 0.0
    ratio = measured.f[lit] / truth[lit]
    assert lit.mean() > 0.9
    # Noise-free: most samples measure their bin's value exactly; a few straddle a bin
    # edge within the rig's beam and footprint (8 % at most here).
    assert np.median(np.abs(ratio - 1.0)) < 1e-6
    assert np.all(np.abs(ratio - 1.0) < 0.2)


def test_named_extremes_are_finite_and_warning_free(glossy):
    """Normal, grazing (z = 0 exactly), wi = wo, wi = −wo on the horizon, random pairs."""
    rng = np.random.default_rng(2)
    v = rng.normal(size=(2, 5000, 3))
    v[..., 2] = np.abs(v[..., 2])
    wi, wo = v / np.linalg.norm(v, axis=-1, keepdims=True)
    grazing = np.array([np.cos(0.7), np.sin(0.7), 0.0])
    named_i = np.array([[0, 0, 1.0], grazing, grazing, -grazing, [0, 0, 1.0], wi[0]])
    named_o = np.array([[0, 0, 1.0], grazing, [0, 0, 1.0], grazing, grazing, wi[0]])
    wi, wo = np.concatenate([wi, named_i]), np.concatenate([wo, named_o])
    with np.errstate(all="raise", under="ignore"):
        f = glossy.eval(wi, wo)
        p = glossy.pdf(wo, wi)
        drawn, q = glossy.sample(wo, rng.random(wo.shape))
    assert np.all(np.isfinite(f)) and np.all(f >= 0.0)
    assert np.all(np.isfinite(p)) and np.all(p >= 0.0)
    assert np.all(np.isfinite(drawn)) and np.all(np.isfinite(q)) and np.all(q >= 0.0)
    np.testing.assert_allclose(np.linalg.norm(drawn, axis=-1), 1.0, atol=1e-14)
