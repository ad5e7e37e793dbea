"""The moment estimate lands near the lobe it reads, and the weights follow."""

from __future__ import annotations

import numpy as np

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.brdf.family import parse
from gonio.reconstruct.starts import starts


def _hemisphere(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _measured(model: brdf.BRDF, n: int = 4000) -> Measured:
    wi, wo = _hemisphere(n, 1), _hemisphere(n, 2)
    f = model.eval(wi, wo)
    return Measured(wi, wo, f, 1e-3 * f + 1e-6, "hybrid", True, None, None, "luminance", "t")  # type: ignore[arg-type]


def test_the_moment_estimate_reads_the_roughness_and_the_weights():
    truth = brdf.create(
        "sum",
        components=[
            {"name": "lambert", "albedo": 0.4},
            {"name": "cook_torrance", "distribution": "beckmann", "alpha": 0.15, "f0": 0.5},
        ],
    )
    family = parse("lambert+beckmann")
    slots = family.slots(rgb=False)
    first = starts(family, slots, _measured(truth), count=3, seed=0)
    albedo, alpha, f0 = first[0]
    assert 0.5 * 0.15 < alpha < 2.0 * 0.15
    assert abs(albedo - 0.4) < 0.1 and 0.2 < f0 < 1.0
    assert len(first) == 3 and not np.allclose(first[1], first[0])


def test_anisotropic_roughness_is_read_per_axis():
    truth = brdf.create("ggx_anisotropic", alpha_x=0.05, alpha_y=0.3, fresnel="none")
    family = parse("ggx_anisotropic:fresnel=none")
    alpha_x, alpha_y = starts(family, family.slots(False), _measured(truth), count=1, seed=0)[0]
    assert alpha_x < alpha_y
    assert 0.5 < (alpha_y / alpha_x) / 6.0 < 2.0


def test_phong_shininess_from_the_mirror_angle():
    truth = brdf.create("phong", n=200.0, ks=0.8)
    family = parse("phong")
    n, ks = starts(family, family.slots(False), _measured(truth), count=1, seed=0)[0]
    assert 50.0 < n < 800.0 and 0.3 < ks <= 1.0


def test_black_data_keep_finite_starts():
    black = brdf.create("lambert", albedo=0.0)
    family = parse("lambert+ggx")
    for x in starts(family, family.slots(False), _measured(black, 200), count=2, seed=0):
        assert np.all(np.isfinite(x))
