"""The RGL export rendered by Mitsuba 3's ``measured`` plugin (the ``render`` extra,
``scalar_spectral`` variant): a sphere under a point light matches, pixel by pixel,
the same sphere shaded in numpy from the analytic model the run measured, within the
reconstruction's own error; and Mitsuba's BSDF evaluates the file as gonio's reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gonio import brdf
from gonio.brdf.rgl import RglTable
from gonio.cli import main
from gonio.radiometry.bands import band_eval
from gonio.types import FloatArray
from tests.support.runs import plan_spec, scene_spec, simulated_run

mi = pytest.importorskip("mitsuba", reason="the render extra (pip install gonio[render])")

MATERIAL = {"name": "cook_torrance", "alpha": 0.3, "kd": 0.2, "f0": 0.04}
SIZE = 32
#: Point light intensity (W/sr), position; camera position and horizontal field of view.
INTENSITY = 30.0
LIGHT = np.array([0.0, 4.0, 3.0])
CAMERA = np.array([0.0, 0.0, 5.0])
FOV_DEG = 30.0
SPP = 64
#: Sub-pixel samples per side of the numpy shading (a box filter, as the film's).
SUB = 8


@pytest.fixture(scope="module")
def exported(runs_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    scene = scene_spec("glossy_metal", material=MATERIAL, noise=False, effects=[])
    run = simulated_run(runs_dir, plan_spec(200), scene)
    out = tmp_path_factory.mktemp("mitsuba") / "run.bsdf"
    assert main(["export", str(run), "--format", "rgl", "-o", str(out), "-q"]) == 0
    return out


def render(path: Path) -> np.ndarray:
    mi.set_variant("scalar_spectral")
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
            "sensor": {
                "type": "perspective",
                "fov": FOV_DEG,
                "fov_axis": "x",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=CAMERA.tolist(), target=[0, 0, 0], up=[0, 1, 0]
                ),
                "film": {
                    "type": "hdrfilm",
                    "width": SIZE,
                    "height": SIZE,
                    "rfilter": {"type": "box"},
                    "pixel_format": "rgb",
                },
                "sampler": {"type": "stratified", "sample_count": SPP, "seed": 1},
            },
            "sphere": {
                "type": "sphere",
                "radius": 1.0,
                "bsdf": {"type": "measured", "filename": str(path)},
            },
            "light": {"type": "point", "position": LIGHT.tolist(), "intensity": INTENSITY},
        }
    )
    return np.array(mi.render(scene), dtype=np.float64)


def shade(f) -> tuple[np.ndarray, np.ndarray]:
    """Radiance (SIZE, SIZE) of the unit sphere seen from CAMERA, lit by the point light,
    one bounce, f(ωi, ωo)·cos θi·I/d², box-filtered over SUB² rays per pixel; and where
    every ray of the pixel hits the lit, visible sphere."""
    t = np.tan(np.radians(FOV_DEG) / 2)
    px = (np.arange(SIZE)[:, None] + (np.arange(SUB) + 0.5)[None] / SUB).ravel()
    col, row = np.meshgrid(px, px)
    d = np.stack([(2 * col / SIZE - 1) * t, (1 - 2 * row / SIZE) * t, -np.ones_like(col)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    b = d @ CAMERA
    disc = b * b - (CAMERA @ CAMERA - 1)
    hit = disc > 0
    p = CAMERA + (-b - np.sqrt(np.maximum(disc, 0)))[..., None] * d
    n = p / np.linalg.norm(p, axis=-1, keepdims=True)
    to_light = LIGHT - p
    dist2 = np.sum(to_light**2, -1)
    tangent = np.cross(n, [1.0, 0.0, 0.0])
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    frame = np.stack([tangent, np.cross(n, tangent), n], -2)  # isotropic: any tangent
    wi = np.einsum("...ij,...j->...i", frame, to_light / np.sqrt(dist2)[..., None])
    wo = np.einsum("...ij,...j->...i", frame, -d)
    ok = hit & (wi[..., 2] > 0) & (wo[..., 2] > 0)
    up = np.array([0.0, 0.0, 1.0])
    value = f(np.where(ok[..., None], wi, up), np.where(ok[..., None], wo, up))
    radiance = np.where(ok, value * wi[..., 2] * INTENSITY / dist2, 0.0)
    blocks = (SIZE, SUB, SIZE, SUB)
    return radiance.reshape(blocks).mean(axis=(1, 3)), ok.reshape(blocks).all(axis=(1, 3))


def test_mitsuba_renders_the_export_as_the_analytic_model_within_its_error(exported: Path) -> None:
    image = render(exported)
    grey = image.mean(axis=-1)
    truth, inside = shade(
        band_eval(brdf.create("cook_torrance", alpha=0.3, kd=0.2, f0=0.04), "luminance")
    )
    read, _ = shade(band_eval(RglTable(exported), "luminance"))
    peak = truth.max()
    assert inside.sum() > 300
    # The spectrum is flat (a luminance run): Mitsuba's RGB is grey up to its
    # wavelength sampling noise.
    assert np.max(np.abs(image - grey[..., None])[inside]) < 0.02 * peak
    # Mitsuba and gonio's reader agree on the file (Monte Carlo noise, float32)…
    assert np.max(np.abs(grey - read)[inside]) < 0.02 * peak
    # …so the image is the analytic sphere within the reconstruction's error.
    error = np.abs(read - truth)
    assert np.all((np.abs(grey - truth) <= error + 0.02 * peak)[inside])
    assert np.median(np.abs(grey - truth)[inside] / truth[inside]) < 0.02


def random_pair(rng: np.random.Generator, theta_max: float) -> tuple[FloatArray, FloatArray]:
    """Two directions uniform in (θ ≤ ``theta_max`` rad, φ)."""
    theta = rng.uniform(0.0, theta_max, 2)
    phi = rng.uniform(-np.pi, np.pi, 2)
    w = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    return w[0], w[1]


def test_mitsuba_evaluates_the_file_as_gonio_reads_it(exported: Path) -> None:
    mi.set_variant("scalar_spectral")
    bsdf = mi.load_dict({"type": "measured", "filename": str(exported)})
    read = RglTable(exported)
    rng = np.random.default_rng(3)
    context = mi.BSDFContext()
    for _ in range(40):
        wi, wo = random_pair(rng, 1.4)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi)
        # Mitsuba's eval is the file's value: f·cos θo.
        got = np.array(bsdf.eval(context, si, mi.Vector3f(*wo))).ravel()
        want = read.eval(wi, wo)[0] * wo[2]
        assert got == pytest.approx(want, rel=1e-4, abs=1e-7)


@pytest.mark.parametrize(
    "phi_nodes",
    [[0.0], [-np.pi, 0.0, np.pi], [-np.pi, -np.pi / 2, 0.0]],
    ids=["isotropic", "anisotropic", "anisotropic-half"],
)
def test_mitsuba_evaluates_a_random_file_as_gonio_reads_it(tmp_path: Path, phi_nodes) -> None:
    """Random tables (no smoothness to hide behind): the warp's inverse with its
    parameter interpolation, the jacobian and the φ mirroring agree with Mitsuba's. An
    isotropic file's sigma is the same at every φ: Mitsuba 3.9.1 leaves the plugin's
    φ reduction unset for isotropic files (it then turns ωi by π when its y > 0), which
    only a φ-dependent sigma would show."""
    from gonio.brdf import tensor_file

    rng = np.random.default_rng(len(phi_nodes))
    n_phi, n_theta = len(phi_nodes), 4

    def table(*shape: int) -> np.ndarray:
        return rng.uniform(0.2, 1.0, shape).astype(np.float32)

    path = tmp_path / "random.bsdf"
    path.write_bytes(
        tensor_file.to_bytes(
            {
                "description": "random",
                "jacobian": np.ones(1, np.uint8),
                "theta_i": np.linspace(0.0, 1.5, n_theta, dtype=np.float32),
                "phi_i": np.asarray(phi_nodes, dtype=np.float32),
                "ndf": table(3, 7),
                "sigma": np.tile(table(1, 5), (3, 1)) if n_phi == 1 else table(3, 5),
                "vndf": table(n_phi, n_theta, 6, 8),
                "luminance": table(n_phi, n_theta, 5, 5),
                "rgb": table(n_phi, n_theta, 3, 5, 5),
            }
        )
    )
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    read = RglTable(path)
    context = mi.BSDFContext()
    for _ in range(60):
        wi, wo = random_pair(rng, 1.5)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi)
        got = np.array(bsdf.eval(context, si, mi.Vector3f(*wo))).ravel()
        assert got == pytest.approx(read.eval(wi, wo) * wo[2], rel=2e-4, abs=1e-6)
