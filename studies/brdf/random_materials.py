"""Materials drawn at random from the model families, for studies and tests of plans that
should hold whatever the material: Cook–Torrance GGX lobes (never Beckmann: the adaptive
plan's default steering family), rough or smooth, dielectric (Schlick F0) or conductor
(complex index), with or without a Lambertian part."""

from __future__ import annotations

import math

import numpy as np

from gonio import brdf
from gonio.types import BrdfEval

#: Range of the GGX roughness α, drawn log-uniform.
ALPHA = (0.03, 0.5)


def draw(seed: int) -> tuple[str, BrdfEval]:
    """A material of seed ``seed``: a short description and its f(ωi, ωo) in sr⁻¹."""
    rng = np.random.default_rng([20261203, seed])
    alpha = float(math.exp(rng.uniform(math.log(ALPHA[0]), math.log(ALPHA[1]))))
    kd = float(rng.uniform(0.05, 0.6)) if rng.random() < 0.5 else 0.0
    params: dict[str, object] = {"alpha": alpha, "distribution": "ggx", "kd": kd}
    if rng.random() < 0.5:
        params |= {"fresnel": "schlick", "f0": float(rng.uniform(0.02, 0.08))}
        what = f"dielectric F0 {params['f0']:.3f}"
    else:
        params |= {
            "fresnel": "conductor",
            "ior": float(rng.uniform(0.1, 2.0)),
            "k": float(rng.uniform(1.0, 8.0)),
        }
        what = f"conductor n {params['ior']:.2f} k {params['k']:.2f}"
    text = f"GGX α {alpha:.3f}, {what}, kd {kd:.2f}"
    return text, brdf.create("cook_torrance", **params).eval
