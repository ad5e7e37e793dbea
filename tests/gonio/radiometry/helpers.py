"""Shared pieces of the radiometry tests: direction builders, models, instruments."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

import gonio.brdf as brdf
from gonio.radiometry import CollimatedSource, DetectorOptics, PointSource
from gonio.types import FloatArray

GRAZING = np.array([1.0, 0.0, 0.0])
NORMAL = np.array([0.0, 0.0, 1.0])


def direction(theta: float | FloatArray, phi: float | FloatArray = 0.0) -> FloatArray:
    """Unit vectors (..., 3) at polar angle θ and azimuth φ (radians)."""
    t, p = np.asarray(theta, dtype=np.float64), np.asarray(phi, dtype=np.float64)
    return np.stack(
        np.broadcast_arrays(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1
    )


def hemisphere(rng: np.random.Generator, n: int) -> FloatArray:
    """n directions uniform in solid angle on the upper hemisphere."""
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return np.asarray(v / np.linalg.norm(v, axis=-1, keepdims=True), dtype=np.float64)


#: The models of the round-trip test (grey and RGB).
MODELS = {
    "lambert": brdf.create("lambert", albedo=0.5),
    "cook_torrance_ggx": brdf.create("cook_torrance", alpha=0.15, kd=0.05),
    "ggx_anisotropic": brdf.create("ggx_anisotropic", alpha_x=0.08, alpha_y=0.4),
    "cook_torrance_rgb": brdf.create("cook_torrance", alpha=0.3, f0=(0.95, 0.64, 0.54), kd=0.0),
    "lambert_rgb": brdf.create("lambert", albedo=(0.2, 0.5, 0.8)),
}

# Hypothesis strategies for instrument constants (log-uniform-ish over decades).
positives = st.floats(min_value=1e-3, max_value=1e3, allow_nan=False, allow_infinity=False)
collimated_sources = st.builds(CollimatedSource, positives, st.floats(1.0, 20.0))
point_sources = st.builds(PointSource, positives, st.floats(50.0, 5000.0))
sources = collimated_sources | point_sources
optics = st.builds(DetectorOptics, st.floats(1e-6, 1e-1), st.floats(1.0, 50.0))
thetas = st.floats(min_value=0.0, max_value=np.pi / 2)
phis = st.floats(min_value=0.0, max_value=2 * np.pi)
