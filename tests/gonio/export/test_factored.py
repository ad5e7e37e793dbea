"""Export as a factored BRDF: the files as docs/reference/formats_factored.md describes them, the
normalizations, the CDFs, the colour fit and the error as J·K grows."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

import gonio.brdf as brdf
from gonio.analysis.measured import Measured
from gonio.cli import main
from gonio.config import ConfigError
from gonio.errors import GonioError
from gonio.export import factored as factored_export
from gonio.export.factored import Factorization, Resolution, export, factorize
from gonio.reconstruct.methods import reconstruction

RES = Resolution(theta_out=8, phi_out=16, theta_p=16, phi_p=32, z=256)
GOLD = {
    "alpha": 0.3,
    "fresnel": "conductor",
    "ior": (0.18, 0.42, 1.37),
    "k": (3.42, 2.35, 1.77),
    "kd": 0.05,
}


def read_by_the_format(path: Path) -> dict[str, object]:
    """The two files read as the format description says, independently of gonio."""
    lines = [s for s in path.read_text().splitlines() if s.strip() and not s.startswith("#")]
    header = {}
    for i, line in enumerate(lines):
        if line == "INTENSITY DATA":
            body = lines[i + 1 :]
            break
        key, value = line.split(":", 1)
        header[key.strip()] = value.strip()
    j, k = int(header["outer terms ('J' in paper)"]), int(header["inner terms ('K' in paper)"])
    n = {key: int(header[key]) for key in header if key.endswith("_count")}
    out: dict[str, object] = {"param": header["param"], "J": j, "K": k, **n}

    def take(label: str, rows: int) -> np.ndarray:
        assert body.pop(0) == label
        values = [np.array(body.pop(0).split(), dtype=float) for _ in range(rows)]
        return np.array(values)

    for jj in range(j):
        out[f"F_{jj}"] = take(f"F_{jj}", n["theta_out_count"])
        out[f"G_{jj}"] = take(f"G_{jj}", n["theta_p_count"])
        for kk in range(k):
            out[f"u_{jj}_{kk}"] = take(f"u_{jj}_{kk}", 1)[0]
            out[f"v_{jj}_{kk}"] = take(f"v_{jj}_{kk}", 1)[0]
    assert body.pop(0) == "COLOR DATA"
    out["Fc"] = take("Fc", n["theta_out_count"]).reshape(n["theta_out_count"], -1, 3)
    out["Gc"] = take("Gc", n["theta_p_count"]).reshape(n["theta_p_count"], -1, 3)
    assert body == ["EOF"]
    cdf = [s for s in Path(f"{path}.cdf").read_text().splitlines() if not s.startswith("#")]
    assert cdf[0] == "CDF DATA"
    assert cdf[-1] == "EOF"
    for i in range(j * k):
        assert cdf[1 + 4 * i] == f"P(phi_p|term {i})"
        assert cdf[3 + 4 * i] == f"P(z|term {i})"
        out[f"cdf_phi_{i}"] = np.array(cdf[2 + 4 * i].split(), dtype=float)
        out[f"cdf_z_{i}"] = np.array(cdf[4 + 4 * i].split(), dtype=float)
    assert len(cdf) == 2 + 4 * j * k
    return out


@pytest.fixture(scope="module")
def gold(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Factorization]:
    path = tmp_path_factory.mktemp("export") / "gold.txt"
    return path, export(brdf.create("cook_torrance", **GOLD), path, 2, 3, RES)


def test_the_files_hold_the_tables_as_the_format_describes(gold):
    path, result = gold
    t = result.tables
    got = read_by_the_format(path)
    assert got["param"] == "halfangle"
    assert (got["J"], got["K"]) == (2, 3)
    assert (got["theta_out_count"], got["phi_out_count"]) == (8, 16)
    assert (got["theta_p_count"], got["phi_p_count"], got["z_count"]) == (16, 32, 256)
    for j in range(2):
        np.testing.assert_array_equal(got[f"F_{j}"], t.F[j])  # 17 digits: exact
        np.testing.assert_array_equal(got[f"G_{j}"], t.G[j])
        for k in range(3):
            np.testing.assert_array_equal(got[f"u_{j}_{k}"], t.u[j, k])
            np.testing.assert_array_equal(got[f"v_{j}_{k}"], t.v[j, k])
            np.testing.assert_array_equal(got[f"cdf_phi_{3 * j + k}"], t.cdf_phi[3 * j + k])
            np.testing.assert_array_equal(got[f"cdf_z_{3 * j + k}"], t.cdf_z[3 * j + k])
    np.testing.assert_array_equal(got["Fc"], t.Fc)
    np.testing.assert_array_equal(got["Gc"], t.Gc)
    again = brdf.create("factored", path=str(path)).tables
    np.testing.assert_array_equal(again.F, t.F)
    np.testing.assert_array_equal(again.cdf_z, t.cdf_z)


def test_the_factors_are_normalized_as_documented(gold):
    t = gold[1].tables
    edges = np.linspace(0.0, np.pi / 2, 17)
    dz = np.cos(edges[:-1]) - np.cos(edges[1:])
    dphi = 2 * np.pi / 32
    np.testing.assert_allclose(np.einsum("jab,a->j", t.G, dz) * dphi, 1.0, rtol=1e-12)
    np.testing.assert_allclose(t.u @ dz, 1.0, rtol=1e-12)
    shares = t.v.sum(axis=-1) * dphi  # ∫ vⱼₖ dφ: inner term k's share of Gⱼ
    np.testing.assert_allclose(shares.sum(axis=1), 1.0, atol=0.05)
    assert all(np.all(a >= 0.0) for a in (t.F, t.G, t.u, t.v, t.Fc, t.Gc))


def test_the_cdfs_integrate_the_inner_terms(gold):
    """The z CDF against a brute-force integral of u(θ(z)) over a fine z grid."""
    t = gold[1].tables
    fine = (np.arange(256 * 64) + 0.5) / (256 * 64)
    theta_bin = np.minimum((np.arccos(1.0 - fine) / (np.pi / 2) * 16).astype(int), 15)
    for i in range(6):
        u, v = t.u[i // 3, i % 3], t.v[i // 3, i % 3]
        mass = u[theta_bin].reshape(256, 64).sum(axis=1)
        np.testing.assert_allclose(t.cdf_z[i], np.cumsum(mass) / mass.sum(), atol=2e-3)
        np.testing.assert_allclose(t.cdf_phi[i], np.cumsum(v) / v.sum(), rtol=1e-12)
        assert t.cdf_z[i][-1] == 1.0
        assert np.all(np.diff(t.cdf_z[i]) >= 0.0)


def test_the_error_falls_as_j_k_grows():
    model = brdf.create("cook_torrance", **GOLD)
    errors = [factorize(model, j, k, RES).error for j, k in ((1, 1), (2, 2), (3, 2), (4, 2))]
    assert all(b < a for a, b in itertools.pairwise(errors))
    assert errors[-1] < 0.6 * errors[0]
    one, two = factorize(model, 2, 1, RES), factorize(model, 2, 2, RES)
    assert one.error >= two.error >= two.outer_error > 0.0


def test_the_colour_factors_recover_a_constant_colour():
    albedo = np.array([0.2, 0.5, 0.9])
    t = factorize(brdf.create("lambert", albedo=tuple(albedo)), 2, 2, RES).tables
    product = t.Fc[:, :, None, None, :] * t.Gc[None, None, :, :, :]
    # Not to rounding: the fit also absorbs part of the intensity's error (4e-6 here).
    expected = np.broadcast_to(albedo / albedo.mean(), product.shape)
    np.testing.assert_allclose(product, expected, rtol=1e-4)


def test_a_grey_model_has_unit_colour_factors(gold):
    t = factorize(brdf.create("lambert", albedo=0.7), 1, 1, RES).tables
    assert np.all(t.Fc == 1.0)
    assert np.all(t.Gc == 1.0)
    assert gold[1].colour_error > 0.0


def test_export_refuses_a_missing_folder_before_the_work_and_bad_term_counts(tmp_path):
    model = brdf.create("lambert", albedo=0.5)
    with pytest.raises(ConfigError, match="does not exist"):
        export(model, tmp_path / "nowhere" / "f.txt", 1, 1, RES)
    with pytest.raises(GonioError, match="K"):
        factorize(model, 1, 17, RES)
    with pytest.raises(GonioError, match="J"):
        factorize(model, 0, 1, RES)
    assert list(tmp_path.iterdir()) == []


def test_a_run_is_factored_from_its_reconstruction(run_file, tmp_path, monkeypatch):
    """`gonio export --format factored` writes what the library writes of the run's
    linear reconstruction filled by its nearest sample (the factorization itself is
    held to its error bounds above); coarse tables keep it quick."""
    coarse = Resolution(theta_out=6, phi_out=12, theta_p=12, phi_p=24, z=64)
    monkeypatch.setattr(factored_export, "Resolution", lambda: coarse)
    out = tmp_path / "run.factored"
    args = ["export", str(run_file), "--format", "factored", "--outer", "2", "--inner", "1"]
    assert main([*args, "-o", str(out), "-q"]) == 0
    surface = reconstruction(Measured.from_run(run_file), "linear", None, extrapolate="nearest")
    export(surface, tmp_path / "library.factored", 2, 1, coarse, seed=0)
    for suffix in ("", ".cdf"):
        cli = (tmp_path / f"run.factored{suffix}").read_bytes()
        assert cli == (tmp_path / f"library.factored{suffix}").read_bytes()
    normal = np.array([0.0, 0.0, 1.0])
    assert brdf.create("factored", path=str(out)).eval(normal, normal) > 0
