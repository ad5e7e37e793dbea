"""Shared pieces of the rig tests: the shipped rigs, direction builders, angle errors."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gonio.rig.model import Rig
from gonio.rig.schema import RigSpec
from gonio.types import FloatArray

RIG_DIR = Path(__file__).resolve().parents[3] / "configs" / "rigs"
RIG_FILES = {"arch": RIG_DIR / "arch.yaml", "in_plane": RIG_DIR / "in_plane.yaml"}
#: The shipped rigs of each kinematic type, loaded once (module-level so hypothesis
#: tests can use them); their lights are collimated.
RIGS = {name: Rig.from_yaml(path) for name, path in RIG_FILES.items()}
#: The arch rig with a point source (for the point-source scene).
ARCH_POINT = Rig.from_yaml(RIG_DIR / "arch_point.yaml")


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


#: Round-trip tolerance (rad) required by the issue.
TOL = 1e-10


def direction(theta_deg: float | FloatArray, phi_deg: float | FloatArray) -> FloatArray:
    """Sample-frame unit vectors (..., 3) at polar angle θ and azimuth φ (degrees)."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack(
        np.broadcast_arrays(np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1
    )


def in_tilted_plane(tilt_deg: float, alpha_deg: float) -> FloatArray:
    """A unit vector in the plane through the x axis whose normal (0, cos e, sin e) is
    ``tilt_deg`` = e above the horizon, at ``alpha_deg`` from the plane's highest
    direction (0, −sin e, cos e) toward +x. An in-plane rig reaches this plane with
    sample_tilt = ∓e and puts the arms at ±α."""
    e, a = np.radians(tilt_deg), np.radians(alpha_deg)
    up = np.array([0.0, -np.sin(e), np.cos(e)])
    return np.asarray(np.cos(a) * up + np.sin(a) * np.array([1.0, 0.0, 0.0]), dtype=np.float64)


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


def wrap(angle: FloatArray) -> FloatArray:
    """Angles to [−π, π)."""
    return np.asarray(np.mod(np.asarray(angle) + np.pi, 2.0 * np.pi) - np.pi, dtype=np.float64)


def column(rig: Rig, axis: str) -> int:
    return rig.axes.index(axis)
