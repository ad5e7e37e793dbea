"""The tabulated MERL BRDF (``create("merl", path=...)``): files written here from the
layout in docs/reference/formats.md (not by gonio's writer), read back, compared with the
analytic model they tabulate, and used as a simulated scene's material."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio import brdf, params
from gonio.analysis.measured import Measured
from gonio.config import ConfigError
from gonio.errors import GonioError
from gonio.radiometry.bands import band_eval
from gonio.scene import load_scene
from tests.support.runs import plan_spec, scene_spec, simulated_run

HALF_PI = np.pi / 2
SCALES = np.array([1.0, 1.15, 1.66]) / 1500.0
#: The interpolation error docs/reference/formats.md states for this model (θh, θd < 80°, all
#: eight corners present): 1 %.
MODEL = brdf.create("cook_torrance", alpha=0.3, kd=(0.5, 0.3, 0.2), f0=0.04)
STATED = 0.01


def centre_pairs():
    """Every bin's centre (θh = ((i+½)/90)²·π/2, θd = (j+½)·π/180, φd = (k+½)·π/180) as a
    pair with φh = 0, and where one exists."""
    n = np.arange(90) + 0.5
    th = ((n / 90) ** 2 * HALF_PI)[:, None, None]
    td = (n / 90 * HALF_PI)[None, :, None]
    pd = ((np.arange(180) + 0.5) / 180 * np.pi)[None, None, :]
    c = np.stack(np.broadcast_arrays(th, 0.0, td, pd), axis=-1)
    p = params.get("rusinkiewicz")
    ok = p.valid(c)
    wi, wo = p.inverse(np.where(ok[..., None], c, 0.0))
    return wi, wo, ok


def write_merl(path: Path, rgb: np.ndarray, missing: np.ndarray) -> Path:
    """rgb (90, 90, 180, 3) in sr⁻¹; missing bins stored as −1."""
    stored = np.moveaxis(rgb, -1, 0) / SCALES[:, None, None, None]
    stored = np.where(missing[None], -1.0, stored)
    path.write_bytes(
        np.array([90, 90, 180], dtype="<i4").tobytes() + stored.astype("<f8").tobytes()
    )
    return path


@pytest.fixture(scope="module")
def centres() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return centre_pairs()


@pytest.fixture(scope="module")
def tables(tmp_path_factory: pytest.TempPathFactory, centres) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("merl")
    wi, wo, ok = centres
    lambert = np.broadcast_to(np.array([0.2, 0.5, 0.8]) / np.pi, (*ok.shape, 3))
    return {
        "model": write_merl(folder / "model.binary", MODEL.eval(wi, wo), ~ok),
        "lambert": write_merl(folder / "lambert.binary", lambert, ~ok),
    }


def _random_pairs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


def test_bin_centres_read_back_exactly(tables, centres):
    table = brdf.create("merl", path=str(tables["model"]))
    assert table.is_rgb and table.isotropic and table.reciprocal
    wi, wo, ok = centres
    sel = (slice(2, 88, 5), slice(2, 88, 5), slice(None, None, 7))
    wi, wo, ok = wi[sel][ok[sel]], wo[sel][ok[sel]], ok[sel][ok[sel]]
    np.testing.assert_allclose(table.eval(wi, wo), MODEL.eval(wi, wo), rtol=1e-9)


def test_interpolation_error_within_the_stated_bound(tables):
    table = brdf.create("merl", path=str(tables["model"]))
    wi, wo = _random_pairs(20_000, 3)
    c = params.get("rusinkiewicz").forward_iso(wi, wo)
    # Bins whose eight interpolation corners exist: tan θh tan θd |cos φd| ≤ 1 at the
    # corners around, which θh, θd < 80° and a margin keep.
    keep = (c[:, 0] < np.radians(80)) & (c[:, 1] < np.radians(80))
    keep &= np.tan(c[:, 0] + 0.03) * np.tan(c[:, 1] + 0.03) < 1
    got, want = table.eval(wi[keep], wo[keep]), MODEL.eval(wi[keep], wo[keep])
    error = np.abs(got - want) / want
    assert keep.sum() > 5000
    assert error.max() < STATED
    assert error.max() > 1e-4  # an interpolation, not a lookup of the model


def test_a_constant_is_exact_and_missing_bins_take_no_part(tables):
    table = brdf.create("merl", path=str(tables["lambert"]))
    wi, wo = _random_pairs(20_000, 4)
    got = table.eval(wi, wo)
    present = np.any(got > 0, axis=-1)
    np.testing.assert_allclose(
        got[present], np.broadcast_to([0.2, 0.5, 0.8], got[present].shape) / np.pi, rtol=1e-12
    )
    # Where every corner is missing (the horizon, both angles near 90°): 0, and rare.
    assert (~present).mean() < 1e-3


def test_reciprocal_and_zero_below_the_horizon(tables):
    table = brdf.create("merl", path=str(tables["model"]))
    wi, wo = _random_pairs(500, 5)
    np.testing.assert_allclose(table.eval(wi, wo), table.eval(wo, wi), rtol=1e-12)
    below = wo * np.array([1, 1, -1])
    below[:, 2] -= 1e-3
    below /= np.linalg.norm(below, axis=-1, keepdims=True)
    assert np.all(table.eval(wi, below) == 0)


def test_a_file_of_another_layout_is_one_line(tmp_path):
    bad = tmp_path / "short.binary"
    bad.write_bytes(np.array([90, 90, 180], dtype="<i4").tobytes() + b"\0" * 80)
    with pytest.raises(GonioError, match="not a MERL BRDF file") as err:
        brdf.create("merl", path=str(bad))
    assert "\n" not in str(err.value)
    with pytest.raises(GonioError, match="cannot read"):
        brdf.create("merl", path=str(tmp_path / "absent.binary"))


def test_a_scene_measures_the_tabulated_material(tables, tmp_path, monkeypatch):
    """A scene whose material is the file, named relative to the scene file: the
    simulated run (noise-free) measures what the analytic model it tabulates gives."""
    folder = tmp_path / "scene"
    folder.mkdir()
    (folder / "table.binary").write_bytes(tables["model"].read_bytes())
    scene = scene_spec(
        "glossy_metal", material={"name": "merl", "path": "table.binary"}, noise=False
    )
    run = simulated_run(folder, plan_spec(40), scene)
    measured = Measured.from_run(run)
    truth = band_eval(MODEL, measured.band)(measured.wi, measured.wo)
    np.testing.assert_allclose(measured.f, truth, rtol=0.02)
    # The run's scene, read back as the truth, finds its table beside the scene file
    # whatever the working directory.
    monkeypatch.chdir(tmp_path)
    np.testing.assert_allclose(measured.scene_truth()(measured.wi, measured.wo), truth, rtol=0.02)


def test_a_scene_naming_a_missing_file_is_one_line_at_the_parameter(tmp_path):
    spec = scene_spec("glossy_metal", material={"name": "merl", "path": "absent.binary"})
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    with pytest.raises(ConfigError) as err:
        load_scene(path)
    message = str(err.value)
    assert "material.path" in message and str(tmp_path / "absent.binary") in message
    assert "\n" not in message


def test_a_block_of_missing_bins_reads_0_inside_and_the_present_mean_at_its_border(
    tmp_path, centres
):
    _, _, ok = centres
    missing = ~ok
    missing[:, 40:50, :] = True  # θd in [40°, 50°) not measured
    rgb = np.broadcast_to(np.array([0.1, 0.2, 0.3]), (*ok.shape, 3))
    table = brdf.create("merl", path=str(write_merl(tmp_path / "hole.binary", rgb, missing)))
    th = np.full(5, np.radians(10.0))
    td = np.radians([39.2, 40.3, 45.0, 49.7, 50.8])
    got = table.at(th, td, np.full(5, 1.0))
    # 39.2°, 40.3° and 49.7°, 50.8° interpolate with present corners only: the constant.
    np.testing.assert_allclose(got[[0, 1, 3, 4]], np.tile([0.1, 0.2, 0.3], (4, 1)), rtol=1e-12)
    np.testing.assert_array_equal(got[2], [0.0, 0.0, 0.0])  # no corner present
