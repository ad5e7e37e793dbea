"""The UTIA anisotropic BRDF file (``create("utia", path=...)``, `gonio.brdf.utia.write`):
files written here from the layout in docs/reference/formats.md#utia (Filip's indexing,
not gonio's writer), read back at and between the nodes, round trips of an anisotropic
and an isotropic model within the stated interpolation error, bad files as one line, and
a scene whose material is such a file."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.brdf import utia
from gonio.cli import main
from gonio.errors import GonioError
from gonio.radiometry.bands import band_eval
from tests.support.runs import CONFIGS, plan_spec, scene_spec, simulated_run

NT, NP = 6, 48
STEP_T, STEP_P = np.radians(15.0), np.radians(7.5)
SIZE = 3 * NT * NP * NT * NP * 8
#: The models of the round trips and the bounds docs/reference/formats.md#utia states
#: for them (both θ ≤ 75°): the largest error as a fraction of the tabulated peak.
ANISOTROPIC = brdf.create("ggx_anisotropic", alpha_x=0.3, alpha_y=0.6, f0=0.9)
ISOTROPIC = brdf.create("cook_torrance", alpha=0.8, f0=0.9, kd=(0.3, 0.2, 0.1))
STATED = {"anisotropic": 0.15, "isotropic": 0.06}
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)


def filip_index(c: int, ti: int, pi: int, tv: int, pv: int) -> int:
    """The flat index of a value as Filip's reader computes it."""
    nc, nr = NP * NT, NP * NT
    return c * nr * nc + nc * (NP * ti + pi) + NP * tv + pv


def write_flat(path: Path, flat: np.ndarray) -> Path:
    path.write_bytes(np.asarray(flat, dtype="<f8").tobytes())
    return path


def direction(theta, phi) -> np.ndarray:
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    s = np.sin(theta)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=-1)


def cap_pairs(n: int, seed: int, theta_max_deg: float = 75.0) -> tuple[np.ndarray, np.ndarray]:
    """Pairs uniform in solid angle with both θ ≤ ``theta_max_deg``."""
    rng = np.random.default_rng(seed)
    z = rng.uniform(np.cos(np.radians(theta_max_deg)), 1.0, (2, n))
    phi = rng.uniform(0.0, 2 * np.pi, (2, n))
    v = direction(np.arccos(z), phi)
    return v[0], v[1]


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("utia")


@pytest.fixture(scope="module")
def flat() -> np.ndarray:
    """Random positive values, one per file entry."""
    return np.random.default_rng(7).uniform(0.1, 2.0, SIZE // 8)


@pytest.fixture(scope="module")
def table(folder: Path, flat: np.ndarray) -> utia.UtiaTable:
    model = brdf.create("utia", path=str(write_flat(folder / "random.bin", flat)))
    assert isinstance(model, utia.UtiaTable)
    return model


@pytest.fixture(scope="module")
def round_trips(folder: Path) -> dict[str, brdf.BRDF]:
    return {
        "anisotropic": brdf.create("utia", path=str(utia.write(folder / "aniso.bin", ANISOTROPIC))),
        "isotropic": brdf.create("utia", path=str(utia.write(folder / "iso.bin", ISOTROPIC))),
    }


nodes = st.tuples(
    st.integers(0, 2),
    st.integers(0, NT - 1),
    st.integers(0, NP - 1),
    st.integers(0, NT - 1),
    st.integers(0, NP - 1),
)


@SETTINGS
@given(node=nodes)
def test_a_node_reads_the_value_at_filips_index(table, flat, node):
    c, ti, pi, tv, pv = node
    got = table.at(ti * STEP_T, pi * STEP_P, tv * STEP_T, pv * STEP_P)[c]
    assert got == flat[filip_index(*node)]


@SETTINGS
@given(
    angles=st.tuples(*(st.floats(0.0, np.radians(89.0)), st.floats(-20.0, 20.0)) * 2),
    turns=st.tuples(st.integers(-3, 3), st.integers(-3, 3)),
)
def test_periodic_in_both_azimuths(table, angles, turns):
    ti, pi, tv, pv = angles
    shifted = table.at(ti, pi + 2 * np.pi * turns[0], tv, pv + 2 * np.pi * turns[1])
    np.testing.assert_allclose(shifted, table.at(ti, pi, tv, pv), rtol=1e-9)


@SETTINGS
@given(
    cell=st.tuples(*(st.integers(0, NT - 2), st.integers(0, NP - 1)) * 2),
    frac=st.tuples(*[st.floats(0.0, 1.0)] * 4),
)
def test_between_nodes_within_the_corners(table, flat, cell, frac):
    """Quadrilinear: a weighted mean of the 16 corners (the φ corner after 352.5° is 0°)."""
    ti, pi, tv, pv = cell
    got = table.at(
        (ti + frac[0]) * STEP_T,
        (pi + frac[1]) * STEP_P,
        (tv + frac[2]) * STEP_T,
        (pv + frac[3]) * STEP_P,
    )
    values = flat.reshape(3, NT, NP, NT, NP)
    corners = values[:, [ti, ti + 1], :, :, :][:, :, [pi, (pi + 1) % NP], :, :][
        :, :, :, [tv, tv + 1], :
    ][..., [pv, (pv + 1) % NP]].reshape(3, -1)
    weights = np.array(
        [
            (1 - frac[0] if a == 0 else frac[0])
            * (1 - frac[1] if b == 0 else frac[1])
            * (1 - frac[2] if c == 0 else frac[2])
            * (1 - frac[3] if d == 0 else frac[3])
            for a in (0, 1)
            for b in (0, 1)
            for c in (0, 1)
            for d in (0, 1)
        ]
    )
    np.testing.assert_allclose(got, corners @ weights, rtol=1e-9)
    assert np.all(got >= corners.min(axis=1) * (1 - 1e-12))
    assert np.all(got <= corners.max(axis=1) * (1 + 1e-12))


def test_beyond_75_degrees_is_the_75_degree_value(table):
    rng = np.random.default_rng(1)
    phi_i, phi_v = rng.uniform(0, 2 * np.pi, (2, 200))
    theta = rng.uniform(np.radians(75.0), np.radians(90.0), (2, 200))
    rim = np.radians(75.0)
    np.testing.assert_array_equal(
        table.at(theta[0], phi_i, theta[1], phi_v), table.at(rim, phi_i, rim, phi_v)
    )
    np.testing.assert_array_equal(
        table.at(theta[0], phi_i, 0.3, phi_v), table.at(rim, phi_i, 0.3, phi_v)
    )


def test_anisotropic_not_reciprocal_and_zero_below_the_horizon(table):
    assert table.is_rgb and not table.isotropic and not table.reciprocal
    wi, wo = cap_pairs(300, 2)
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90° about z
    assert not np.allclose(table.eval(wi @ turn.T, wo @ turn.T), table.eval(wi, wo))
    assert not np.allclose(table.eval(wi, wo), table.eval(wo, wi))
    below = wo * np.array([1.0, 1.0, -1.0])
    assert np.all(table.eval(wi, below) == 0)
    got = table.eval(wi.reshape(3, 100, 3), wo.reshape(3, 100, 3))
    assert got.shape == (3, 100, 3) and got.dtype == np.float64


@pytest.mark.parametrize("kind", ["anisotropic", "isotropic"])
def test_round_trip_exact_at_the_nodes(round_trips, kind):
    model = ANISOTROPIC if kind == "anisotropic" else ISOTROPIC
    wi, wo = utia.grid_directions()
    want = np.asarray(model.eval(wi, wo))
    want = want if model.is_rgb else np.repeat(want[..., None], 3, axis=-1)
    np.testing.assert_allclose(round_trips[kind].eval(wi, wo), want, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("kind", ["anisotropic", "isotropic"])
def test_round_trip_between_nodes_within_the_stated_bound(round_trips, kind):
    model = ANISOTROPIC if kind == "anisotropic" else ISOTROPIC
    wi, wo = cap_pairs(20_000, 3)
    got = round_trips[kind].eval(wi, wo)
    want = np.asarray(model.eval(wi, wo))
    want = want if model.is_rgb else want[..., None]
    peak = utia.tabulate(model).max(axis=(1, 2, 3, 4))
    error = np.abs(got - want).max(axis=0) / peak
    assert np.all(error < STATED[kind])
    assert np.all(error > 1e-3)  # an interpolation, not a lookup of the model


def test_a_grid_rotation_of_an_isotropic_model_is_exact_an_anisotropic_one_is_not(round_trips):
    wi, wo = cap_pairs(500, 4)
    c, s = np.cos(STEP_P * 5), np.sin(STEP_P * 5)  # 37.5°: five azimuth steps
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    iso, aniso = round_trips["isotropic"], round_trips["anisotropic"]
    np.testing.assert_allclose(iso.eval(wi @ turn.T, wo @ turn.T), iso.eval(wi, wo), rtol=1e-9)
    rotated, plain = aniso.eval(wi @ turn.T, wo @ turn.T), aniso.eval(wi, wo)
    assert np.max(np.abs(rotated - plain) / plain) > 0.1


def test_negative_values_read_as_zero_and_srgb_decodes(folder, flat):
    values = flat.copy()
    values[filip_index(1, 2, 3, 4, 5)] = -0.25
    values[filip_index(0, 0, 0, 0, 0)] = 140.0
    path = write_flat(folder / "signed.bin", values)
    linear = brdf.create("utia", path=str(path))
    assert linear.at(2 * STEP_T, 3 * STEP_P, 4 * STEP_T, 5 * STEP_P)[1] == 0.0
    srgb = brdf.create("utia", path=str(path), encoding="srgb")
    assert srgb.at(0.0, 0.0, 0.0, 0.0)[0] == pytest.approx(100.0)
    v = flat[filip_index(2, 1, 1, 1, 1)]
    want = 100 * (v / 140 / 12.92 if v / 140 <= 0.04045 else ((v / 140 + 0.055) / 1.055) ** 2.4)
    assert srgb.at(STEP_T, STEP_P, STEP_T, STEP_P)[2] == pytest.approx(want, rel=1e-12)
    with pytest.raises(GonioError, match="encoding must be one of linear, srgb"):
        brdf.create("utia", path=str(path), encoding="gamma")


def _bad_files(folder: Path, flat: np.ndarray) -> dict[str, tuple[Path, str]]:
    nan, inf = flat.copy(), flat.copy()
    nan[filip_index(2, 5, 47, 0, 1)] = np.nan
    inf[filip_index(0, 1, 0, 0, 0)] = np.inf
    huge = folder / "huge.bin"
    with open(huge, "wb") as stream:  # sparse: no disk used, 10 GB announced
        stream.truncate(10**10)
    return {
        "truncated": (write_flat(folder / "short.bin", flat[:-1]), "1990648 bytes"),
        "longer": (write_flat(folder / "long.bin", np.append(flat, 1.0)), "1990664 bytes"),
        "merl-sized": (huge, "10000000000 bytes, expected 1990656"),
        "nan": (write_flat(folder / "nan.bin", nan), "nan at channel B, θi 75°, φi 352.5°"),
        "inf": (write_flat(folder / "inf.bin", inf), "inf at channel R, θi 15°, φi 0°"),
        "absent": (folder / "absent.bin", "cannot read the UTIA file"),
        "a folder": (folder, "not a UTIA BRDF file"),
    }


def test_a_bad_file_is_one_line_naming_it(folder, flat):
    for what, (path, expected) in _bad_files(folder, flat).items():
        with pytest.raises(GonioError) as err:
            brdf.create("utia", path=str(path))
        message = str(err.value)
        assert expected in message and str(path.name) in message, what
        assert "\n" not in message, what


def _scene(folder: Path, material: dict[str, str]) -> Path:
    path = folder / "scene.yaml"
    path.write_text(yaml.safe_dump(scene_spec("brushed_metal", material=material, noise=False)))
    return path


def test_gonio_simulate_with_a_broken_file_exits_2_with_one_line(tmp_path, flat):
    nan = flat.copy()
    nan[3] = np.nan
    write_flat(tmp_path / "broken.bin", nan)
    scene = _scene(tmp_path, {"name": "utia", "path": "broken.bin"})
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["simulate", str(CONFIGS / "plans/quick.yaml"), "--scene", str(scene), "-q"])
    assert code == 2
    lines = err.getvalue().strip().splitlines()
    assert len(lines) == 1 and "material.path" in lines[0]
    assert str(tmp_path / "broken.bin") in lines[0] and "expected finite numbers" in lines[0]


def test_a_scene_measures_the_tabulated_material(round_trips, folder, tmp_path, monkeypatch):
    """A scene whose material is a UTIA file named relative to the scene file: the
    simulated run (noise-free) measures what the table gives, from any folder."""
    scene_folder = tmp_path / "scene"
    scene_folder.mkdir()
    (scene_folder / "brushed.bin").write_bytes((folder / "aniso.bin").read_bytes())
    scene = scene_spec(
        "brushed_metal", material={"name": "utia", "path": "brushed.bin"}, noise=False
    )
    run = simulated_run(scene_folder, plan_spec(40, isotropic=False), scene)
    measured = Measured.from_run(run)
    truth = band_eval(round_trips["anisotropic"], measured.band)(measured.wi, measured.wo)
    np.testing.assert_allclose(measured.f, truth, rtol=0.02)
    monkeypatch.chdir(tmp_path)
    np.testing.assert_allclose(measured.scene_truth()(measured.wi, measured.wo), truth, rtol=0.02)
