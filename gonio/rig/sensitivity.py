"""How a rig's joint-angle errors reach the measured pair's directions, a
parametrization's coordinates and a BRDF value, to first order.

Sources, per axis, independent, as standard deviations of the joint angle (rad):

- **quantization**: the encoder reads whole motor ticks, 2π/4096 through the axis's
  gear (`drivers.dynamixel.axis.AxisConfig.resolution_rad`); the true motor angle is
  anywhere within ±½ tick of the reading: σ = tick/√12.
- **repeatability**: Gaussian at the joint, downstream of the encoder (a belt, a worm, a
  coupling), so the read-back angles never see it. The rig file has no such field; the
  simulator's ``position_error.repeatability_deg`` supplies it (0.02° in
  configs/scenes/brushed_metal.yaml, 0 by default).

Chain: J_q = ∂(si, ti, so, to)/∂q (..., 4, A), the arc-length displacement of each
direction along its tangent frame (e_θ, e_φ) (`gonio.params.conditioning.pair_frame`)
per radian of each joint, by central differences of `Rig.forward` with
`KINEMATIC_STEP` (forward kinematics is a product of rotations: entries O(1), errors
about step²/6 ≈ 2e-13 and ε/step ≈ 2e-10). Directions: Σ_ω = J_q Σ_q J_qᵀ.
Coordinates: J_c = `tangent_jacobian` · J_q, standard errors √diag(J_c Σ_q J_cᵀ).
BRDF: δf = ∇f · δω with ∇f along the same frame (central differences of ``eval``,
`BRDF_STEP`), σ_f = √(∇f Σ_ω ∇fᵀ). That one does not depend on the parametrization:
f read through any parametrization's inverse at the recorded coordinates has the same
first-order error (chain rule), so a parametrization changes where a measured value is
filed, not the value.

Alignment: the rig's measured alignment (``rig.alignment_file``) states each fitted
parameter's standard error; J_p = ∂(si, ti, so, to)/∂p over the parameters of
`gonio.rig.alignment_fit.parameters` (central differences of the aligned forward map at
the commanded angles, `ALIGNMENT_STEP`), Σ_ω = J_p Σ_p J_pᵀ (`alignment_sigma`), Σ_p the
covariance the file states (`gonio.rig.alignment_fit.stated_covariance`: standard errors
and correlations; a parameter it could not determine adds nothing, the file names it
with what would determine it).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gonio.brdf import BRDF
from gonio.errors import DomainError
from gonio.params import pair_frame, tangent_jacobian
from gonio.rig.alignment_fit import as_alignment, stated_covariance, vector
from gonio.rig.model import Rig
from gonio.types import ArrayLike, FloatArray

#: Central-difference step (rad) of `kinematic_jacobian`.
KINEMATIC_STEP = 2.0**-20
#: Central-difference step (rad, mm) of `alignment_jacobian`.
ALIGNMENT_STEP = 2.0**-20
#: Largest central-difference step (rad of arc) of `brdf_gradient`; a quarter of the
#: lower direction's z when that is smaller, so no step crosses the horizon.
BRDF_STEP = 2.0**-20


@dataclass(frozen=True)
class AxisErrors:
    """Per-axis standard deviations of the joint angle (rad), in the rig's axis order."""

    tick: FloatArray  # one encoder tick through the axis's gear
    quantization: FloatArray  # tick/√12
    repeatability: FloatArray

    @property
    def total(self) -> FloatArray:
        """Quantization and repeatability combined (independent)."""
        return np.asarray(np.hypot(self.quantization, self.repeatability), dtype=np.float64)


def axis_errors(rig: Rig, repeatability_rad: float = 0.0) -> AxisErrors:
    """The rig's encoder quantization per axis, with ``repeatability_rad`` (1σ) on each."""
    tick = np.array([a.resolution_rad for a in rig.bus_axes()], dtype=np.float64)
    return AxisErrors(tick, tick / math.sqrt(12.0), np.full_like(tick, repeatability_rad))


def kinematic_jacobian(rig: Rig, angles: ArrayLike) -> FloatArray:
    """∂(si, ti, so, to)/∂q (..., 4, A) at joint angles ``angles`` (..., A)."""
    q = np.asarray(angles, dtype=np.float64)
    wi, wo = rig.forward(q)
    frame = pair_frame(wi, wo)  # (..., 6, 4)
    columns = []
    for j in range(q.shape[-1]):
        step = np.zeros(q.shape[-1])
        step[j] = KINEMATIC_STEP
        (ai, ao), (bi, bo) = rig.forward(q + step), rig.forward(q - step)
        moved = np.concatenate([ai - bi, ao - bo], axis=-1) / (2.0 * KINEMATIC_STEP)
        columns.append(np.einsum("...k,...kc->...c", moved, frame))
    return np.asarray(np.stack(columns, axis=-1), dtype=np.float64)


def _covariance(jacobian: FloatArray, sigma: ArrayLike) -> FloatArray:
    """J diag(σ²) Jᵀ over stacked Jacobians (..., m, A)."""
    s2 = np.asarray(sigma, dtype=np.float64) ** 2
    return np.asarray(np.einsum("...ia,a,...ja->...ij", jacobian, s2, jacobian), np.float64)


def direction_covariance(rig: Rig, angles: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Σ_ω (..., 4, 4): covariance of the pair's tangent displacements (rad²)."""
    return _covariance(kinematic_jacobian(rig, angles), sigma)


def direction_sigma(rig: Rig, angles: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """RMS angular error (rad) of one direction of the pair: √(trace Σ_ω / 2)."""
    cov = direction_covariance(rig, angles, sigma)
    return np.asarray(np.sqrt(np.trace(cov, axis1=-2, axis2=-1) / 2.0), dtype=np.float64)


def coordinate_sigma(name: str, rig: Rig, angles: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Standard errors (..., 4) of parametrization ``name``'s coordinates of the pair the
    rig measures at ``angles``, from joint errors ``sigma`` (A,) (rad; radii unitless)."""
    wi, wo = rig.forward(np.asarray(angles, dtype=np.float64))
    jc = tangent_jacobian(name, wi, wo) @ kinematic_jacobian(rig, angles)
    return np.asarray(np.sqrt(np.einsum("...ii->...i", _covariance(jc, sigma))), np.float64)


class GreyModel(Protocol):
    """What `brdf_gradient` needs of a model: grey values f(wi, wo) (sr⁻¹) at pairs
    (..., 3) (a `BRDF`, or an estimate from measured samples)."""

    is_rgb: bool

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray: ...


def brdf_gradient(model: GreyModel, wi: ArrayLike, wo: ArrayLike) -> FloatArray:
    """∂f/∂(si, ti, so, to) (..., 4) in sr⁻¹/rad, for a grey model, at pairs above the
    horizon (central differences on the moved pair (ω + s e)/‖ω + s e‖)."""
    if model.is_rgb:
        raise DomainError(f"brdf_gradient needs a grey model, got an RGB {model!r}")
    wi, wo = np.asarray(wi, np.float64), np.asarray(wo, np.float64)
    lowest = np.minimum(wi[..., 2], wo[..., 2])
    if not np.all(lowest > 0.0):
        raise DomainError(
            "brdf_gradient needs both directions above the horizon (f is 0 on it); "
            f"{int(np.sum(~(lowest > 0.0)))} pair(s) are not"
        )
    step = np.minimum(BRDF_STEP, 0.25 * lowest)[..., None]
    frame = pair_frame(wi, wo)
    out = []
    for j in range(4):
        e = frame[..., j]
        ends = []
        for sign in (1.0, -1.0):
            a = wi + sign * step * e[..., :3]
            b = wo + sign * step * e[..., 3:]
            a /= np.linalg.norm(a, axis=-1, keepdims=True)
            b /= np.linalg.norm(b, axis=-1, keepdims=True)
            ends.append(model.eval(a, b))
        out.append((ends[0] - ends[1]) / (2.0 * step[..., 0]))
    return np.asarray(np.stack(out, axis=-1), dtype=np.float64)


def brdf_sigma(model: BRDF, rig: Rig, angles: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Standard error (...) of f (sr⁻¹) at the pair measured at ``angles``, from joint
    errors ``sigma`` (A,): √(∇f Σ_ω ∇fᵀ)."""
    q = np.asarray(angles, dtype=np.float64)
    g = brdf_gradient(model, *rig.forward(q))
    cov = direction_covariance(rig, q, sigma)
    return np.asarray(np.sqrt(np.einsum("...i,...ij,...j->...", g, cov, g)), dtype=np.float64)


def alignment_jacobian(
    rig: Rig, angles: ArrayLike, which: Sequence[int] | None = None
) -> FloatArray:
    """∂(si, ti, so, to)/∂p (..., 4, P) of the pair measured at the commanded ``angles``
    (..., A) per unit of each alignment parameter (`gonio.rig.alignment_fit.parameters`
    order; only those indexed by ``which``, in its order, where given)."""
    q = np.asarray(angles, dtype=np.float64)
    p = vector(rig, rig.alignment)
    frame = pair_frame(*rig.forward(q, rig.alignment))
    columns = []
    for k in range(len(p)) if which is None else which:
        step = np.zeros_like(p)
        step[k] = ALIGNMENT_STEP
        ai, ao = rig.forward(q, as_alignment(rig, p + step))
        bi, bo = rig.forward(q, as_alignment(rig, p - step))
        moved = np.concatenate([ai - bi, ao - bo], axis=-1) / (2.0 * ALIGNMENT_STEP)
        columns.append(np.einsum("...k,...kc->...c", moved, frame))
    return np.asarray(np.stack(columns, axis=-1), dtype=np.float64)


def alignment_covariance(rig: Rig, angles: ArrayLike) -> FloatArray:
    """Σ_ω (..., 4, 4) (rad²) of the pair measured at ``angles`` (..., A) from the
    covariance the rig's alignment file states: J_p Σ_p J_pᵀ."""
    stated = stated_covariance(rig)
    which = np.flatnonzero(np.diag(stated) > 0)  # the others add nothing: not differenced
    if not len(which):
        return np.zeros((*np.shape(angles)[:-1], 4, 4))
    jac = alignment_jacobian(rig, angles, which.tolist())
    block = stated[np.ix_(which, which)]
    return np.asarray(np.einsum("...ip,pq,...jq->...ij", jac, block, jac), dtype=np.float64)


def alignment_brdf_sigma(model: GreyModel, rig: Rig, angles: ArrayLike) -> FloatArray:
    """Standard error (...) of f (sr⁻¹) at the pair measured at ``angles`` (..., A) from
    the uncertainty of the rig's measured alignment: √(∇f Σ_ω ∇fᵀ), ∇f of ``model`` at
    the pair the rig's alignment puts there."""
    q = np.asarray(angles, dtype=np.float64)
    g = brdf_gradient(model, *rig.forward(q, rig.alignment))
    cov = alignment_covariance(rig, q)
    return np.asarray(np.sqrt(np.einsum("...i,...ij,...j->...", g, cov, g)), dtype=np.float64)


def alignment_sigma(rig: Rig, angles: ArrayLike) -> FloatArray:
    """RMS angular error (rad) of one direction of the pair measured at ``angles``
    (..., A) from the uncertainty of the rig's measured alignment: √(trace Σ_ω / 2)."""
    cov = alignment_covariance(rig, angles)
    return np.asarray(np.sqrt(np.trace(cov, axis1=-2, axis2=-1) / 2.0), dtype=np.float64)
