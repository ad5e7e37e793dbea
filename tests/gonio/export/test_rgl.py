"""The RGL writer (`gonio.export.rgl`): a run exported by the command line and read
back by gonio's reader and by a parser written here from the tensor_file layout in
docs/reference/formats.md#rgl; analytic models written and read back within the
stated interpolation bound; RGB written as RGB and as an upsampled spectrum."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.brdf.rgl import RglTable
from gonio.cli import main
from gonio.export.rgl import fields, write
from gonio.output import reserve_output
from gonio.radiometry.bands import band_eval
from gonio.reconstruct.methods import reconstruction
from gonio.store import open_run
from tests.support.runs import plan_spec, scene_spec, simulated_run

#: The rough material the exported run measures (noise and instrument effects off).
MATERIAL = {"name": "cook_torrance", "alpha": 0.3, "kd": 0.2, "f0": 0.04}
#: The documented bound: |f_read − f| ≤ BOUND × max f over θi, θo ≤ 80° (models of
#: α ≥ 0.1 at the default resolution; docs/results/rgl.md measures it), and
#: `BOUND_DIFFUSE` with a Lambertian part up to kd = 0.5 (9.7 % measured at α = 0.1).
BOUND = 0.05
BOUND_DIFFUSE = 0.12
DTYPES = {1: "u1", 2: "i1", 3: "u2", 4: "i2", 5: "u4", 6: "i4", 7: "u8", 8: "i8", 9: "f2"}
DTYPES |= {10: "f4", 11: "f8"}


def parse(path: Path) -> dict[str, tuple[int, np.ndarray]]:
    """name → (offset, array): 12 bytes 'tensor_file\\0', version (u8, u8), count (u32);
    per field name length (u16), name, rank (u16), type (u8), offset (u64), shape
    (rank × u64); little-endian."""
    raw = path.read_bytes()
    assert raw[:12] == b"tensor_file\0"
    assert struct.unpack_from("<BB", raw, 12) == (1, 0)
    (count,) = struct.unpack_from("<I", raw, 14)
    at, out = 18, {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", raw, at)
        name = raw[at + 2 : at + 2 + n].decode()
        at += 2 + n
        rank, code, offset = struct.unpack_from("<HBQ", raw, at)
        at += 11
        shape = struct.unpack_from(f"<{rank}Q", raw, at)
        at += 8 * rank
        dtype = np.dtype("<" + DTYPES[code])
        size = int(np.prod(shape)) * dtype.itemsize
        assert offset + size <= len(raw)
        out[name] = (offset, np.frombuffer(raw[offset : offset + size], dtype).reshape(shape))
    return out


class Model:
    """An analytic model seen as a reconstruction supported everywhere."""

    def __init__(self, model: brdf.BRDF) -> None:
        self.model = model

    def eval(self, wi, wo):
        return self.model.eval(wi, wo)

    def supported(self, wi, wo):
        return np.ones(np.shape(wi)[:-1], dtype=bool)


def hemisphere(n: int, seed: int, max_deg: float = 80.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    theta = np.arccos(rng.uniform(np.cos(np.radians(max_deg)), 1.0, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)


def written(tmp: Path, model: object, **kwargs: object) -> Path:
    path = tmp / "model.bsdf"
    with reserve_output(path, "-o") as out:
        write(out, model, **kwargs)  # type: ignore[arg-type]
    return path


@pytest.fixture(scope="module")
def rough_run(runs_dir: Path) -> Path:
    scene = scene_spec("glossy_metal", material=MATERIAL, noise=False, effects=[])
    return simulated_run(runs_dir, plan_spec(200), scene)


@pytest.fixture(scope="module")
def exported(rough_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rgl") / "run.bsdf"
    assert main(["export", str(rough_run), "--format", "rgl", "-o", str(out), "-q"]) == 0
    return out


def test_the_command_line_writes_the_documented_layout(exported: Path) -> None:
    table = parse(exported)
    names = {"description", "jacobian", "theta_i", "phi_i", "wavelengths", "spectra"}
    assert names | {"ndf", "sigma", "vndf", "luminance"} == set(table)
    for offset, _ in table.values():
        assert offset % 8 == 0
    arrays = {k: a for k, (_, a) in table.items()}
    assert arrays["jacobian"].tolist() == [1]
    assert "cook_torrance" not in bytes(arrays["description"]).decode()  # the run, not its truth
    assert "luminance band" in bytes(arrays["description"]).decode()
    n_theta = len(arrays["theta_i"])
    assert arrays["phi_i"].shape == (1,) and arrays["phi_i"].dtype == np.float32
    assert arrays["vndf"].shape[:2] == (1, n_theta)
    lam = arrays["wavelengths"]
    assert arrays["spectra"].shape[:3] == (1, n_theta, len(lam))
    assert arrays["luminance"].shape == (1, n_theta, *arrays["spectra"].shape[3:])
    # A one-band (luminance) run: a spectrum flat over the visible.
    spectra = arrays["spectra"]
    assert np.allclose(spectra, spectra[:, :, :1], rtol=1e-6, atol=0)
    assert lam[0] <= 360 and lam[-1] >= 830
    for name in ("ndf", "sigma", "vndf", "luminance", "spectra", "theta_i"):
        assert arrays[name].dtype == np.float32 and np.all(np.isfinite(arrays[name]))


def test_the_run_reads_back_as_its_reconstruction(exported: Path, rough_run: Path) -> None:
    surface = reconstruction(
        Measured.from_run(open_run(rough_run)), "linear", None, extrapolate="nearest"
    )
    read = RglTable(exported)
    wi, wo = hemisphere(3000, 1, 70.0), hemisphere(3000, 2, 70.0)
    got = band_eval(read, "luminance")(wi, wo)
    want = np.asarray(surface.eval(wi, wo))
    truth = band_eval(brdf.create("cook_torrance", alpha=0.3, kd=0.2, f0=0.04), "luminance")(wi, wo)
    assert np.all(np.isfinite(got))
    # A piecewise-linear reconstruction has kinks the file's bilinear tables round off:
    # the bound holds for 99 % of the pairs, and the typical error is far below it.
    assert np.quantile(np.abs(got - want), 0.99) <= BOUND * np.max(want)
    assert np.median(np.abs(got - want) / want) < 0.01
    assert np.median(np.abs(got - truth) / truth) < 0.02


@settings(max_examples=4, deadline=None)
@given(alpha=st.floats(0.1, 0.6), kd=st.floats(0.0, 0.5))
def test_a_microfacet_model_reads_back_within_the_bound(
    tmp_path_factory: pytest.TempPathFactory, alpha: float, kd: float
) -> None:
    model = brdf.create("cook_torrance", alpha=alpha, kd=kd, f0=0.04)
    read = RglTable(written(tmp_path_factory.mktemp("m"), Model(model)))
    wi, wo = hemisphere(4000, 3), hemisphere(4000, 4)
    want = model.eval(wi, wo)
    got = band_eval(read, "luminance")(wi, wo)
    bound = BOUND if kd == 0.0 else BOUND_DIFFUSE
    assert np.max(np.abs(got - want)) <= bound * np.max(want)


def test_rgb_is_written_as_rgb_and_as_a_spectrum_that_reads_back_the_same(tmp_path: Path) -> None:
    model = brdf.create("cook_torrance", alpha=0.25, kd=(0.5, 0.3, 0.1), f0=(0.9, 0.6, 0.3))
    wi, wo = hemisphere(2000, 5), hemisphere(2000, 6)
    want = model.eval(wi, wo)
    (tmp_path / "rgb").mkdir()
    (tmp_path / "spectral").mkdir()
    as_rgb = RglTable(written(tmp_path / "rgb", Model(model), color="rgb"))
    as_spectrum = RglTable(written(tmp_path / "spectral", Model(model), color="spectral"))
    assert as_rgb.material.wavelengths is None
    assert as_spectrum.material.wavelengths is not None
    a, b = as_rgb.eval(wi, wo), as_spectrum.eval(wi, wo)
    assert np.max(np.abs(a - b)) <= 1e-5 * np.max(a)  # the upsampling reads back exactly
    for c in range(3):
        assert np.max(np.abs(a[:, c] - want[:, c])) <= BOUND * np.max(want[:, c])


@pytest.mark.parametrize("band", ["r", "g", "b"])
def test_a_one_band_reconstruction_reads_back_in_its_band(tmp_path: Path, band: str) -> None:
    model = brdf.create("cook_torrance", alpha=0.4, kd=0.3, f0=0.04)
    table, _ = fields(Model(model), band=band, color="spectral")
    spectra = table["spectra"]
    assert isinstance(spectra, np.ndarray)
    lit = spectra[0, 5, :, 10, 10] > 0
    assert 0 < lit.sum() < len(lit)  # flat over the band's box only
    read = RglTable(written(tmp_path, Model(model), band=band))
    wi, wo = hemisphere(500, 7), hemisphere(500, 8)
    got = band_eval(read, band)(wi, wo)
    want = model.eval(wi, wo)
    assert np.max(np.abs(got - want)) <= BOUND * np.max(want)


def test_a_bad_colour_is_refused_on_the_command_line(exported: Path, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "export",
                str(exported),
                "--format",
                "rgl",
                "--rgl-color",
                "cmyk",
                "-o",
                str(tmp_path / "x"),
            ]
        )
    assert exc.value.code == 2
