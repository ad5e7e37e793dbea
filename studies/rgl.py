"""RGL material files (Dupuy & Jakob 2018): round-trip error of analytic models, and
Mitsuba 3's rendering of an export.

Run: ``.venv/bin/python studies/rgl.py`` (about a minute on 2 cores). Prints the
machine; per model and resolution (incident elevations × warped samples per side),
the error of f read back from the file written by `gonio.export.rgl` against the
model at 20 000 random pairs (uniform in solid angle) with both elevations at most
60°, 80° and 89°: the largest |Δf| and the 99th percentile of |Δf|, each over the
largest f of the region, and the median of |Δf|/f; the write time and the file size.
Then, with the ``render`` extra: a simulated run of a rough dielectric (200 targets,
noise off) exported and rendered by Mitsuba 3's ``measured`` plugin (a 32×32 sphere
under a point light, 64 samples per pixel, ``scalar_spectral``), compared pixel by
pixel (pixels fully covered by the lit sphere) with the sphere shaded in numpy from
the file (gonio's reader) and from the analytic model; and Mitsuba's BSDF evaluation
of the file against gonio's reader at 2000 random pairs.
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import numpy as np
from _machine import describe

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import gonio.brdf as brdf
from gonio.brdf import RglTable
from gonio.export import SAMPLES, THETA_I, write
from gonio.output import reserve_output
from gonio.radiometry import band_eval

MODELS = (
    ("cook_torrance α=0.5, kd=0.2", {"alpha": 0.5, "kd": 0.2, "f0": 0.04}),
    ("cook_torrance α=0.3, kd=0.2", {"alpha": 0.3, "kd": 0.2, "f0": 0.04}),
    ("cook_torrance α=0.2", {"alpha": 0.2, "f0": 0.04}),
    ("cook_torrance α=0.1", {"alpha": 0.1, "f0": 0.04}),
    ("cook_torrance α=0.125, kd=0.5", {"alpha": 0.125, "kd": 0.5, "f0": 0.04}),
    (
        "cook_torrance gold α=0.2 (RGB)",
        {"alpha": 0.2, "fresnel": "conductor", "ior": (0.18, 0.42, 1.37), "k": (3.42, 2.35, 1.77)},
    ),
    ("cook_torrance α=0.05", {"alpha": 0.05, "f0": 0.04}),
)
RESOLUTIONS = ((THETA_I, SAMPLES), (32, 64))
LIMITS_DEG = (60.0, 80.0, 89.0)
PAIRS = 20_000


class Everywhere:
    """A model seen as a reconstruction supported everywhere."""

    def __init__(self, model: brdf.BRDF) -> None:
        self.model = model

    def eval(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return self.model.eval(wi, wo)

    def supported(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        return np.ones(np.shape(wi)[:-1], dtype=bool)


def hemisphere(rng: np.random.Generator, n: int) -> np.ndarray:
    z = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)


def round_trips(folder: Path) -> None:
    rng = np.random.default_rng(7)
    wi, wo = hemisphere(rng, PAIRS), hemisphere(rng, PAIRS)
    elevation = np.degrees(np.arccos(np.minimum(wi[:, 2], wo[:, 2])))  # the larger θ
    print("\n| model | resolution | region | max abs Δf / max f | p99 abs Δf / max f |", end="")
    print(" median abs Δf / f | write (s) | size (MB) |")
    print("|---|---|---|---:|---:|---:|---:|---:|")
    for label, params in MODELS:
        model = brdf.create("cook_torrance", **params)  # type: ignore[arg-type]
        want = band_eval(model, "luminance")(wi, wo)
        for nodes, samples in RESOLUTIONS:
            path = folder / "model.bsdf"
            started = time.perf_counter()
            with reserve_output(path, "-o") as out:
                write(out, Everywhere(model), theta_nodes=nodes, samples=samples)
            wall = time.perf_counter() - started
            size = path.stat().st_size / 1e6
            got = band_eval(RglTable(path), "luminance")(wi, wo)
            for limit in LIMITS_DEG:
                sel = elevation <= limit
                err = np.abs(got[sel] - want[sel])
                peak = np.max(want[sel])
                median = np.median(err / np.maximum(want[sel], 1e-300))
                print(
                    f"| {label} | {nodes} × {samples}² | θ ≤ {limit:.0f}° "
                    f"| {np.max(err) / peak:.4f} | {np.quantile(err, 0.99) / peak:.4f} "
                    f"| {median:.4f} | {wall:.2f} | {size:.1f} |",
                    flush=True,
                )


def mitsuba(folder: Path) -> None:
    try:
        from tests.gonio.export import test_rgl_mitsuba as scene  # the render extra
    except Exception as exc:  # pytest's skip, or mitsuba missing
        print(f"\nMitsuba: not installed ({type(exc).__name__}); install gonio[render]")
        return
    import mitsuba as mi

    from gonio.cli import main
    from tests.support.runs import plan_spec, scene_spec, simulated_run

    spec = scene_spec("glossy_metal", material=scene.MATERIAL, noise=False, effects=[])
    with contextlib.redirect_stdout(io.StringIO()):  # the acquisition's own report
        run = simulated_run(folder, plan_spec(200), spec)
    exported = folder / "run.bsdf"
    assert main(["export", str(run), "--format", "rgl", "-o", str(exported), "-q"]) == 0
    started = time.perf_counter()
    image = scene.render(exported)
    wall = time.perf_counter() - started
    grey = image.mean(axis=-1)
    model = brdf.create("cook_torrance", alpha=0.3, kd=0.2, f0=0.04)
    truth, inside = scene.shade(band_eval(model, "luminance"))
    read, _ = scene.shade(band_eval(RglTable(exported), "luminance"))
    peak = truth.max()
    print(f"\nMitsuba {mi.__version__} ({scene.SIZE}×{scene.SIZE}, {scene.SPP} spp): ", end="")
    print(f"render {wall:.2f} s; {int(inside.sum())} pixels fully on the lit sphere")
    print("\n| image against | max abs Δ / peak | median abs Δ / value |")
    print("|---|---:|---:|")
    for name, other in (
        ("numpy, from the file (gonio's reader)", read),
        ("numpy, the analytic model", truth),
    ):
        d = np.abs(grey - other)[inside]
        print(f"| {name} | {d.max() / peak:.4f} | {np.median(d / other[inside]):.4f} |")
    d = np.abs(read - truth)[inside]
    print(f"| (the file's shading against the model) | {d.max() / peak:.4f} | ", end="")
    print(f"{np.median(d / truth[inside]):.4f} |")
    channels = np.abs(image - grey[..., None])[inside]
    print(f"\nlargest channel spread of the grey image: {channels.max() / peak:.4f} of the peak")
    mi.set_variant("scalar_spectral")
    bsdf = mi.load_dict({"type": "measured", "filename": str(exported)})
    reader = RglTable(exported)
    rng = np.random.default_rng(11)
    wi, wo = hemisphere(rng, 2000), hemisphere(rng, 2000)
    context, worst = mi.BSDFContext(), 0.0
    mine = reader.eval(wi, wo)[:, 0] * wo[:, 2]
    for k in range(len(wi)):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi[k])
        theirs = float(np.array(bsdf.eval(context, si, mi.Vector3f(*wo[k]))).ravel()[0])
        worst = max(worst, abs(theirs - mine[k]) / max(abs(mine[k]), 1e-6))
    print(f"Mitsuba's eval against gonio's reader, 2000 pairs: largest relative gap {worst:.2e}")


def main() -> None:
    print(describe())
    with tempfile.TemporaryDirectory() as tmp:
        round_trips(Path(tmp))
        mitsuba(Path(tmp))


if __name__ == "__main__":
    _report.run(main, __file__, __doc__, title="RGL material files: round trip and Mitsuba")
