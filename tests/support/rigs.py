"""Helpers for tests that use a rig: variants of a rig, direction builders in the
sample frame (degrees), angles between directions. The shipped rigs themselves are the
session fixtures of tests/conftest.py (`rigs`, `rig`, `arch_point`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from gonio.rig.model import Rig
from gonio.rig.schema import RigSpec
from gonio.types import FloatArray


def rig_with(rig: Rig, **sections: Any) -> Rig:
    """``rig`` with some fields of its sections replaced, e.g.
    ``rig_with(rig, detector={"readout_s": 0.004})`` (validated as a rig file is)."""
    data = rig.spec.model_dump()
    for key, value in sections.items():
        data[key] = {**data[key], **value} if isinstance(value, dict) else value
    return Rig(RigSpec.model_validate(data))


def with_point_source(rig: Rig, distance_mm: float = 300.0) -> Rig:
    """``rig`` with a point source ``distance_mm`` from the sample instead of its beam."""
    return rig_with(
        rig,
        light={"kind": "point", "distance_mm": distance_mm},
        constraints={"beam_diameter_mm": None},
    )


def direction(theta_deg: float | FloatArray, phi_deg: float | FloatArray) -> FloatArray:
    """Sample-frame unit vectors (..., 3) at polar angle θ and azimuth φ (degrees)."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack(
        np.broadcast_arrays(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1
    )


def uniform_directions(rng: np.random.Generator, n: int, theta_max: float) -> FloatArray:
    """n directions uniform (in solid angle) on the cap θ ≤ theta_max (rad)."""
    z = rng.uniform(np.cos(theta_max), 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def angle_between(a: FloatArray, b: FloatArray) -> FloatArray:
    """The angle (rad) between unit vectors, accurate for tiny angles."""
    return np.asarray(
        2.0 * np.arctan2(np.linalg.norm(a - b, axis=-1), np.linalg.norm(a + b, axis=-1)),
        dtype=np.float64,
    )
