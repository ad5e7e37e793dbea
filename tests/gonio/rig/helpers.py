"""Pieces used only by the rig tests: the round-trip tolerance, axis columns, angle
wrapping and the in-plane rig's tilted planes (shared helpers are in tests/support)."""

from __future__ import annotations

import numpy as np

from gonio.rig.model import Rig
from gonio.types import FloatArray

#: Round-trip tolerance (rad) required by the issue.
TOL = 1e-10


def in_tilted_plane(tilt_deg: float, alpha_deg: float) -> FloatArray:
    """A unit vector in the plane through the x axis whose normal (0, cos e, sin e) is
    ``tilt_deg`` = e above the horizon, at ``alpha_deg`` from the plane's highest
    direction (0, −sin e, cos e) toward +x. An in-plane rig reaches this plane with
    sample_tilt = ∓e and puts the arms at ±α."""
    e, a = np.radians(tilt_deg), np.radians(alpha_deg)
    up = np.array([0.0, -np.sin(e), np.cos(e)])
    return np.asarray(np.cos(a) * up + np.sin(a) * np.array([1.0, 0.0, 0.0]), dtype=np.float64)


def wrap(angle: FloatArray) -> FloatArray:
    """Angles to [−π, π)."""
    return np.asarray(np.mod(np.asarray(angle) + np.pi, 2.0 * np.pi) - np.pi, dtype=np.float64)


def column(rig: Rig, axis: str) -> int:
    return rig.axes.index(axis)
