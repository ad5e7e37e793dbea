"""The RGL reader (`gonio.brdf.rgl`), its container (`gonio.brdf.tensor_file`) and its
interpolant (`gonio.brdf.marginal`): hand-built files evaluate as the layout says, the
warp's inverse inverts it, colours reduce as documented, and bad files are one
`GonioError` line naming the file, from Python and from a scene on the command line."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from gonio import brdf
from gonio.brdf import rgl, tensor_file
from gonio.brdf.marginal import Marginal2D, Table
from gonio.brdf.material import MaterialSpec
from gonio.cli import main
from gonio.errors import GonioError
from tests.support.runs import SCENES, plan_spec


def fields(**changes: object) -> dict[str, object]:
    """A small valid isotropic RGB file's fields: constant tables, ``jacobian`` 0."""
    n = 4
    out: dict[str, object] = {
        "description": "a test material",
        "jacobian": np.zeros(1, dtype=np.uint8),
        "theta_i": np.linspace(0, 1.5, 3, dtype=np.float32),
        "phi_i": np.zeros(1, dtype=np.float32),
        "ndf": np.ones((2, 5), dtype=np.float32),
        "sigma": np.ones((2, 5), dtype=np.float32),
        "vndf": np.ones((1, 3, 6, 6), dtype=np.float32),
        "luminance": np.ones((1, 3, n, n), dtype=np.float32),
        "rgb": np.broadcast_to(
            np.array([0.1, 0.2, 0.3], dtype=np.float32)[:, None, None], (1, 3, 3, n, n)
        ).copy(),
    }
    for key, value in changes.items():
        if value is None:
            del out[key]
        else:
            out[key] = value
    return out


def save(path: Path, **changes: object) -> Path:
    path.write_bytes(tensor_file.to_bytes(fields(**changes)))  # type: ignore[arg-type]
    return path


def pairs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2]) + 0.05
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


def test_a_constant_file_holds_f_times_cos_theta_o(tmp_path: Path) -> None:
    model = brdf.create("rgl", path=save(tmp_path / "c.bsdf"))
    assert model.is_rgb and model.name == "rgl"
    wi, wo = pairs(200, 1)
    want = np.array([0.1, 0.2, 0.3]) / wo[:, 2:3]
    assert np.allclose(model.eval(wi, wo), want, rtol=1e-6)
    assert np.all(model.eval(wi, -wo) == 0)  # below the horizon


def test_the_jacobian_multiplies_by_ndf_over_four_sigma(tmp_path: Path) -> None:
    ndf = np.tile(np.linspace(1.0, 3.0, 5, dtype=np.float32), (2, 1))  # bilinear in u(θm)
    path = save(tmp_path / "j.bsdf", jacobian=np.ones(1, np.uint8), ndf=ndf, sigma=2 * ndf)
    wi, wo = pairs(200, 2)
    half = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    u_m = np.sqrt(np.arccos(np.clip(half[:, 2], -1, 1)) / (np.pi / 2))
    u_i = np.sqrt(np.arccos(wi[:, 2]) / (np.pi / 2))
    ratio = (1 + 2 * u_m) / (4 * 2 * (1 + 2 * u_i))
    want = np.array([0.1, 0.2, 0.3]) * (ratio / wo[:, 2])[:, None]
    assert np.allclose(brdf.create("rgl", path=path).eval(wi, wo), want, rtol=1e-5)


def test_a_flat_spectrum_reads_grey_and_its_band_value(tmp_path: Path) -> None:
    lam = np.arange(360, 831, 10, dtype=np.float32)
    spectra = np.full((1, 3, len(lam), 4, 4), 0.25, dtype=np.float32)
    path = save(tmp_path / "s.bsdf", rgb=None, spectra=spectra, wavelengths=lam)
    model = brdf.create("rgl", path=path)
    wi, wo = pairs(50, 3)
    f = model.eval(wi, wo) * wo[:, 2:3]
    assert np.allclose(f, 0.25, rtol=1e-6)


def test_the_colour_matching_functions_and_the_reduction() -> None:
    xyz = rgl.cie1931(np.array([442.0, 555.0, 600.0]))
    assert xyz[1, 1] == pytest.approx(1.0, abs=0.01)  # ȳ(555 nm) = 1
    assert xyz[2, 0] == pytest.approx(1.062, abs=0.01)  # x̄(600 nm)
    assert xyz[0, 2] == pytest.approx(1.75, abs=0.1)  # z̄ near its peak
    lam = np.arange(360.0, 831.0, 10.0)
    assert np.allclose(np.ones(len(lam)) @ rgl.reduction(lam), 1.0)


@settings(max_examples=25, deadline=None)
@given(rgb=hnp.arrays(np.float64, 3, elements=st.floats(-1, 2)))
def test_upsampling_reads_back_the_same_rgb(rgb: np.ndarray) -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    spectrum = rgb @ rgl.upsampling(lam)
    assert np.allclose(spectrum @ rgl.reduction(lam), rgb, atol=1e-12)


def test_grey_upsamples_flat() -> None:
    lam = np.arange(360.0, 831.0, 10.0)
    assert np.allclose(np.full(3, 0.7) @ rgl.upsampling(lam), 0.7)


@settings(max_examples=25, deadline=None)
@given(
    values=hnp.arrays(np.float64, (3, 2, 5, 4), elements=st.floats(0.05, 10)),
    seed=st.integers(0, 1000),
)
def test_the_warp_inverts_its_sampling(values: np.ndarray, seed: int) -> None:
    warp = Marginal2D(values, (np.array([0.0, 1.0, 3.0]), np.array([0.0, 2.0])))
    rng = np.random.default_rng(seed)
    s = rng.uniform(0, 1, (100, 2))
    param = (rng.uniform(-0.5, 3.5, 100), rng.uniform(-0.5, 2.5, 100))
    assert np.allclose(warp.invert(warp.sample(s, param), param), s, atol=1e-9)


def test_the_warp_samples_its_density() -> None:
    rng = np.random.default_rng(4)
    warp = Marginal2D(rng.uniform(0.1, 1.0, (7, 9)))
    u = warp.sample(rng.uniform(0, 1, (200_000, 2)))
    hist, _, _ = np.histogram2d(u[:, 1], u[:, 0], bins=(6, 8), range=((0, 1), (0, 1)))
    cells = np.stack(np.meshgrid((np.arange(8) + 0.5) / 8, (np.arange(6) + 0.5) / 6), -1)
    expected = warp.eval(cells) * 200_000 / 48
    assert np.allclose(hist, expected, rtol=0.1)


def test_a_table_is_bilinear_and_exact_at_its_nodes() -> None:
    values = np.arange(12.0).reshape(3, 4)
    table = Table(values)
    y, x = np.meshgrid(np.linspace(0, 1, 3), np.linspace(0, 1, 4), indexing="ij")
    assert np.allclose(table.eval(np.stack([x, y], -1)), values)
    assert table.eval(np.array([0.5, 0.25])) == pytest.approx(np.mean(values[:2, 1:3]))


@settings(max_examples=20, deadline=None)
@given(
    data=hnp.arrays(
        st.sampled_from([np.uint8, np.int16, np.uint32, np.int64, np.float32, np.float64]),
        hnp.array_shapes(min_dims=0, max_dims=4, max_side=4),
        elements={"min_value": 0, "max_value": 100},
    ),
    name=st.text(min_size=0, max_size=12),
)
def test_the_container_round_trips(tmp_path_factory, data: np.ndarray, name: str) -> None:
    path = tmp_path_factory.mktemp("t") / "f.tensor"
    path.write_bytes(tensor_file.to_bytes({name: data, "other": "text"}))
    read = tensor_file.read(path)
    assert read[name].dtype == data.dtype and read[name].shape == data.shape
    assert np.array_equal(read[name], data)
    assert bytes(read["other"]) == b"text"


def header(count: int = 1) -> bytes:
    return b"tensor_file\0" + struct.pack("<BBI", 1, 0, count)


BAD = {
    "empty": (b"", "shorter than its header"),
    "magic": (b"tensor_fil\0\0" + struct.pack("<BBI", 1, 0, 0), "does not start with"),
    "version": (b"tensor_file\0" + struct.pack("<BBI", 2, 0, 0), "version (2, 0)"),
    "many fields": (header(2**32 - 1), "more than its"),
    "huge shape": (
        header()
        + struct.pack("<H", 1)
        + b"a"
        + struct.pack("<HBQ", 2, 10, 64)
        + struct.pack("<2Q", 2**40, 2**40),
        "runs past the end",
    ),
    "huge rank": (
        header() + struct.pack("<H", 1) + b"a" + struct.pack("<HBQ", 60000, 10, 64),
        "rank 60000",
    ),
    "type": (header() + struct.pack("<H", 1) + b"a" + struct.pack("<HBQ", 0, 12, 0), "type code"),
    "name": (header() + struct.pack("<H", 200) + b"ab" * 10, "truncated in field 0"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_a_bad_container_is_one_line_naming_the_file(tmp_path: Path, case: str) -> None:
    raw, words = BAD[case]
    path = tmp_path / "bad.bsdf"
    path.write_bytes(raw + b"\0" * 40 if case in ("huge shape",) else raw)
    with pytest.raises(GonioError) as exc:
        brdf.create("rgl", path=path)
    message = str(exc.value)
    assert "\n" not in message and str(path) in message and words in message


@settings(max_examples=30, deadline=None)
@given(cut=st.integers(0, 10_000))
def test_every_truncation_is_refused(tmp_path_factory, cut: int) -> None:
    raw = tensor_file.to_bytes(fields())  # type: ignore[arg-type]
    path = tmp_path_factory.mktemp("cut") / "cut.bsdf"
    path.write_bytes(raw[: cut % len(raw)])
    with pytest.raises(GonioError, match=r"cut\.bsdf"):
        rgl.read_material(path)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"ndf": np.full((2, 5), np.nan, np.float32)}, "field ndf: expected finite"),
        ({"vndf": None}, "field vndf: expected a field of that name"),
        ({"sigma": np.ones((2, 5), np.float64)}, "field sigma: expected float32"),
        ({"vndf": np.ones((1, 2, 6, 6), np.float32)}, "field vndf: expected shape"),
        ({"theta_i": np.array([0, 1, 1], np.float32)}, "field theta_i: expected increasing"),
        ({"sigma": np.zeros((2, 5), np.float32)}, "field sigma: expected positive"),
        ({"vndf": np.zeros((1, 3, 6, 6), np.float32)}, "no slice of zero density"),
        ({"jacobian": np.ones(2, np.uint8)}, "field jacobian: expected shape [1]"),
        (
            {"rgb": np.full((1, 3, 3, 4, 4), 3e38, np.float32)},
            "RGL field rgb: values up to 3e+38 (144 beyond 1e+08); expected at most 1e+08",
        ),
        ({"ndf": np.full((2, 5), -1e30, np.float32)}, "RGL field ndf: values up to 1e+30"),
    ],
)
def test_a_bad_field_is_one_line_naming_it(tmp_path: Path, change, words: str) -> None:
    path = save(tmp_path / "bad.bsdf", **change)
    with pytest.raises(GonioError) as exc:
        brdf.create("rgl", path=path)
    assert words in str(exc.value) and str(path.resolve()) in str(exc.value)


def test_a_scene_names_the_file_relative_to_itself(tmp_path: Path) -> None:
    save(tmp_path / "m.bsdf")
    spec = MaterialSpec.model_validate(
        {"name": "rgl", "path": "m.bsdf"}, context={"path": str(tmp_path / "scene.yaml")}
    )
    assert spec.params["path"] == str((tmp_path / "m.bsdf").resolve())
    assert spec.model().name == "rgl"


def test_a_bad_file_in_a_scene_exits_2_in_one_line(tmp_path: Path, capsys) -> None:
    (tmp_path / "bad.bsdf").write_bytes(b"not a tensor file at all")
    scene = yaml.safe_load((SCENES / "glossy_metal.yaml").read_text())
    scene["material"] = {"name": "rgl", "path": "bad.bsdf"}
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(scene))
    (tmp_path / "plan.yaml").write_text(yaml.safe_dump(plan_spec(10)))
    code = main(["simulate", str(tmp_path / "plan.yaml"), "--scene", str(tmp_path / "scene.yaml")])
    err = capsys.readouterr().err
    assert code == 2
    assert "bad.bsdf" in err and "tensor_file" in err and "Traceback" not in err


def test_leading_axes_broadcast_as_for_any_model(tmp_path: Path) -> None:
    ndf = np.tile(np.linspace(1.0, 3.0, 5, dtype=np.float32), (2, 1))
    model = brdf.create(
        "rgl", path=save(tmp_path / "a.bsdf", jacobian=np.ones(1, np.uint8), ndf=ndf)
    )
    wi, wo = pairs(20, 5)
    grid = model.eval(wi.reshape(4, 5, 3), wo.reshape(4, 5, 3))
    assert grid.shape == (4, 5, 3)
    assert np.array_equal(grid.reshape(20, 3), model.eval(wi, wo))
    assert model.eval(wi.reshape(4, 5, 3), wo[0]).shape == (4, 5, 3)
