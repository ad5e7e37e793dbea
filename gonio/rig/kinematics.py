"""Forward kinematics of chains of revolute axes, vectorized.

A chain is a list of unit rotation axes, each expressed in the frame left by the ones
before it (lab frame first). Its rotation is R = R(a₁, θ₁) R(a₂, θ₂) … R(aₙ, θₙ), which
maps vectors from the chain's last frame into the lab frame. The light and the
detector point along a fixed vector of their last frame; the sample chain maps the
sample frame (z = normal) into the lab, so a lab direction d is R_sampleᵀ d in the
sample frame.
"""

from __future__ import annotations

import numpy as np

from gonio.types import FloatArray


def rotation(axis: FloatArray, angle: FloatArray) -> FloatArray:
    """Rotation matrices (..., 3, 3) about the unit ``axis`` (3,) by ``angle`` (...) rad
    (Rodrigues: I + sin θ K + (1 − cos θ) K²)."""
    theta = np.asarray(angle, dtype=np.float64)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    k2 = k @ k
    s = np.sin(theta)[..., None, None]
    c = (1.0 - np.cos(theta))[..., None, None]
    return np.asarray(np.eye(3) + s * k + c * k2, dtype=np.float64)


def chain_rotation(axes: list[FloatArray], angles: list[FloatArray]) -> FloatArray:
    """R = R(a₁, θ₁) … R(aₙ, θₙ), shape broadcast(angles) + (3, 3)."""
    out = rotation(axes[0], angles[0])
    for axis, angle in zip(axes[1:], angles[1:], strict=True):
        out = out @ rotation(axis, angle)
    return out


def apply(matrix: FloatArray, vector: FloatArray) -> FloatArray:
    """``matrix`` (..., 3, 3) times ``vector`` (..., 3) or (3,)."""
    return np.asarray(np.einsum("...ij,...j->...i", matrix, vector), dtype=np.float64)


def apply_transposed(matrix: FloatArray, vector: FloatArray) -> FloatArray:
    """``matrix``ᵀ (..., 3, 3) times ``vector`` (..., 3)."""
    return np.asarray(np.einsum("...ji,...j->...i", matrix, vector), dtype=np.float64)


def rotate_z(vectors: FloatArray, angle: FloatArray) -> FloatArray:
    """Vectors (..., 3) rotated about z by ``angle`` (...) rad."""
    c, s = np.cos(angle), np.sin(angle)
    x, y, z = vectors[..., 0], vectors[..., 1], vectors[..., 2]
    return np.stack([c * x - s * y, s * x + c * y, z], axis=-1)
