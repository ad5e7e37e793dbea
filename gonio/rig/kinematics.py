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

_EYE = np.eye(3)


def skew(axis: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(K, K²) of a unit ``axis``: K v = axis × v."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return k, k @ k


def rotation_of(k: tuple[FloatArray, FloatArray], angle: FloatArray) -> FloatArray:
    """Rotation matrices (..., 3, 3) by ``angle`` (...) rad about the unit axis whose
    (K, K²) are given (Rodrigues: I + sin θ K + (1 − cos θ) K²)."""
    theta = np.asarray(angle, dtype=np.float64)
    s = np.sin(theta)[..., None, None]
    c = (1.0 - np.cos(theta))[..., None, None]
    return np.asarray(_EYE + s * k[0] + c * k[1], dtype=np.float64)


def chain_rotation_of(
    skews: list[tuple[FloatArray, FloatArray]], angles: list[FloatArray]
) -> FloatArray:
    """R = R(a₁, θ₁) … R(aₙ, θₙ), shape broadcast(angles) + (3, 3), from each axis's
    (K, K²) (`skew`)."""
    out = rotation_of(skews[0], angles[0])
    for k, angle in zip(skews[1:], angles[1:], strict=True):
        out = out @ rotation_of(k, angle)
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
