"""The factored representation of Lawrence et al. 2004: error, time, sampling.

Run: ``.venv/bin/python studies/factored.py`` (about 2 minutes on 2 cores). Prints
the machine; the relative Frobenius error of the intensity matrix (outer J terms, all
J·K terms, RGB with the colour factors) and the time of each factorization at the
default resolution; the export time and file sizes; the sampler's speed; per view
angle the share of draws below the horizon and the per-sample variance of the albedo
estimate ∫ f cos θi dωi under cosine sampling, the factored sampler (f cos θi, as
gonio writes it), the paper's literal f cos θo, and the paper's literal term selection
(probability ∝ Fⱼ(ωo) for each of the K inner terms of j, their energies ignored).
``--sampling-only`` skips the error table (the slow part).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # _report

import _report
import numpy as np
from _machine import describe

import gonio.brdf as brdf
from gonio.brdf import directional_albedo
from gonio.export import Resolution, export, factorize
from gonio.params import direction

GOLD = {
    "alpha": 0.2,
    "fresnel": "conductor",
    "ior": (0.18, 0.42, 1.37),
    "k": (3.42, 2.35, 1.77),
    "kd": 0.05,
}
MODELS = (
    ("cook_torrance gold α=0.2, kd=0.05 (RGB)", brdf.create("cook_torrance", **GOLD)),
    ("blinn_phong n=50, ks=0.8, kd=0.2", brdf.create("blinn_phong", n=50.0, ks=0.8, kd=0.2)),
    ("lambert 0.8", brdf.create("lambert", albedo=0.8)),
)
TERMS = ((1, 1), (2, 1), (2, 2), (4, 2), (4, 4), (8, 2), (8, 4))
VIEWS_DEG = (0.0, 30.0, 60.0, 80.0)
DRAWS = 400_000


class SeedCosine:
    """The model with the view's cosine: its table is the paper's f cos θo."""

    def __init__(self, model: brdf.BRDF) -> None:
        self.model = model

    def eval(self, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
        ratio = wo[..., 2] / np.maximum(wi[..., 2], 1e-300)
        f = self.model.eval(wi, wo)
        return f * (ratio[..., None] if self.model.is_rgb else ratio)


def error_table() -> None:
    print("\n| model | J | K | L | outer error | J·K-term error | RGB error | time (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for label, model in MODELS:
        terms = TERMS if model.is_rgb else ((1, 1), (2, 2), (4, 4), (8, 4))
        for j, k in terms:
            t0 = time.perf_counter()
            r = factorize(model, j, k)
            dt = time.perf_counter() - t0
            rgb = f"{r.colour_error:.4f}" if model.is_rgb else "—"
            print(
                f"| {label} | {j} | {k} | {j * k} | {r.outer_error:.4f} | {r.error:.4f} "
                f"| {rgb} | {dt:.2f} |"
            )


def albedo_variances(folder: Path) -> None:
    model = MODELS[0][1]
    res = Resolution()
    t0 = time.perf_counter()
    ours = export(model, folder / "gold.txt", 4, 2, res)
    dt = time.perf_counter() - t0
    sizes = [(folder / n).stat().st_size for n in ("gold.txt", "gold.txt.cdf")]
    print(f"\nexport of the gold model, J = 4, K = 2, {res}: {dt:.2f} s; ", end="")
    print(f"factor file {sizes[0] / 1e6:.2f} MB, CDF file {sizes[1] / 1e6:.2f} MB")
    print(f"error {ours.error:.4f}")
    export(SeedCosine(model), folder / "seed.txt", 4, 2, res)
    seed_selection = brdf.create("factored", path=str(folder / "gold.txt"))
    seed_selection._energy = np.ones_like(seed_selection._energy)  # type: ignore[attr-defined]
    samplers = {
        "f cos θi": brdf.create("factored", path=str(folder / "gold.txt")),
        "paper f cos θo": brdf.create("factored", path=str(folder / "seed.txt")),
        "paper selection": seed_selection,
    }
    rng = np.random.default_rng(1)
    wo = np.broadcast_to(direction(0.5, 0.3), (DRAWS, 3))
    t0 = time.perf_counter()
    samplers["f cos θi"].sample(wo, rng.random((DRAWS, 3)))
    rate = DRAWS / (time.perf_counter() - t0)
    print(f"sampler: {rate / 1e6:.2f} M draws/s (draw + density, L = 8)")
    print(
        "\n| θo | albedo (quadrature, green) | below horizon (f cos θi) | var cosine "
        "| var f cos θi | var paper f cos θo | var paper selection | cosine / f cos θi |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for deg in VIEWS_DEG:
        theta = np.radians(deg)
        w = np.broadcast_to(direction(theta, 0.3), (DRAWS, 3))
        truth = float(directional_albedo(model, theta, 0.3)[1])
        r = rng.random((DRAWS, 2))
        s = np.sqrt(r[:, 0])
        cos_dirs = np.stack(
            [
                s * np.cos(2 * np.pi * r[:, 1]),
                s * np.sin(2 * np.pi * r[:, 1]),
                np.sqrt(1 - r[:, 0]),
            ],
            axis=-1,
        )
        var = {"cosine": float(np.var(model.eval(cos_dirs, w)[:, 1] * np.pi))}
        below = 0.0
        for name, sampler in samplers.items():
            wi, pdf = sampler.sample(w, rng.random((DRAWS, 3)))
            lit = (wi[:, 2] > 0.0) & (pdf > 0.0)
            x = np.zeros(DRAWS)
            x[lit] = model.eval(wi[lit], w[lit])[:, 1] * wi[lit, 2] / pdf[lit]
            assert abs(x.mean() - truth) < 5 * x.std() / np.sqrt(DRAWS), (name, deg)
            var[name] = float(np.var(x))
            if name == "f cos θi":
                below = float(np.mean(wi[:, 2] < 0.0))
        print(
            f"| {deg:.0f}° | {truth:.4f} | {below:.3f} | {var['cosine']:.4f} "
            f"| {var['f cos θi']:.4f} | {var['paper f cos θo']:.4f} | {var['paper selection']:.4f} "
            f"| {var['cosine'] / var['f cos θi']:.1f} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sampling-only", action="store_true", help="skip the error table")
    args = parser.parse_args()
    print(describe())
    print(f"resolution: {Resolution()}")
    if not args.sampling_only:
        error_table()
    with tempfile.TemporaryDirectory() as folder:
        albedo_variances(Path(folder))


if __name__ == "__main__":
    _report.run(
        main, __file__, __doc__, title="The factored representation of Lawrence et al. 2004"
    )
