"""Inverse kinematics in a misaligned rig's true geometry (`gonio.rig.alignment`): the
joint angles to command so that the rig, as it really is, measures a target pair.

Exact parts first: the sample's tilt by solving the closed form for the pair in the
stage's frame (ω_stage = R_tilt ω), the zero offsets by commanding q − δ for the true
joint angles q. What no closed form covers (the light's and the detector's pointing
errors, a point source's height) is taken up by Gauss–Newton steps on the true forward
map from that start: each step solves the damped normal equations of the residual's
Jacobian (central differences), so the rig's 4 axes meet the pair's 4 degrees of
freedom to ~1e-15. A pair the steps do not reach (a pose at a singularity of the chain,
where the start is far off) is reported as not converged, and refused by the caller.

With an isotropic plan the sample rotation stays at its commanded home: the residual
is then what the pair keeps under a turn about the true normal (cos θi, cos θo and
ωi · ωo), met by the other axes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from gonio.types import BoolArray, FloatArray

#: The most Gauss–Newton steps: from a start within a few degrees the error falls below
#: 1e-15 in three or four; an isotropic pair's three invariants, from a start several
#: degrees off, up to ten or more. Only the pairs not yet settled (`SETTLED`) step on.
STEPS = 20
#: The central difference's step (rad): truncation ~H² and rounding ~1e-16 / H both
#: near 1e-11 of the Jacobian, which only slows the last step's convergence.
H = 1e-5
#: Damping of the normal equations, relative to their scale: finite at a singular
#: Jacobian (a pose where an axis does not move the pair), negligible elsewhere.
DAMPING = 1e-12
#: The largest residual component of a reached pair (unit vectors' components).
TOLERANCE = 1e-12
#: Every residual component below this: no further step changes anything.
SETTLED = 1e-14


def newton(
    residual: Callable[[FloatArray, np.ndarray], FloatArray],
    q: FloatArray,
    free: Sequence[int],
    steps: int = STEPS,
) -> tuple[FloatArray, BoolArray]:
    """Joint angles (M, A) from the start ``q`` that make ``residual(q[rows], rows)``
    (rows, M') vanish, moving only the axes ``free``; and where it did (TOLERANCE).
    Each step moves only the rows not yet settled (`SETTLED`)."""
    q = np.array(q, dtype=np.float64)
    free = list(free)
    eye = np.eye(len(free))
    rows = np.arange(len(q))
    for _ in range(steps):
        r = residual(q[rows], rows)
        moving = np.max(np.abs(r), axis=-1, initial=0.0) >= SETTLED
        rows, r = rows[moving], r[moving]
        if not len(rows):
            break
        at = q[rows]
        jac = np.empty((*r.shape, len(free)))
        for k, j in enumerate(free):
            step = np.zeros(q.shape[-1])
            step[j] = H
            jac[..., k] = (residual(at + step, rows) - residual(at - step, rows)) / (2.0 * H)
        jt = np.swapaxes(jac, -1, -2)
        normal = jt @ jac
        scale = np.trace(normal, axis1=-2, axis2=-1)[..., None, None]
        normal = normal + (DAMPING * scale + 1e-300) * eye
        delta = np.linalg.solve(normal, -(jt @ r[..., None]))[..., 0]
        at[:, free] += np.where(np.isfinite(delta), delta, 0.0)
        q[rows] = at
    everything = np.arange(len(q))
    converged = np.max(np.abs(residual(q, everything)), axis=-1, initial=0.0) < TOLERANCE
    return q, np.asarray(converged, dtype=np.bool_)


def pair_residual(
    forward: Callable[[FloatArray], tuple[FloatArray, FloatArray]],
    wi: FloatArray,
    wo: FloatArray,
    isotropic: bool,
) -> Callable[[FloatArray, np.ndarray], FloatArray]:
    """The residual of commanded angles (rows, A) against the target pairs ``wi``,
    ``wo`` (M, 3) of those rows: the six components' misses, or with ``isotropic`` the
    misses of what a turn about the normal keeps."""

    def residual(q: FloatArray, rows: np.ndarray) -> FloatArray:
        ai, ao = forward(q)
        ti, to = wi[rows], wo[rows]
        if not isotropic:
            return np.concatenate([ai - ti, ao - to], axis=-1)
        return np.stack(
            [
                ai[..., 2] - ti[..., 2],
                ao[..., 2] - to[..., 2],
                np.sum(ai * ao, axis=-1) - np.sum(ti * to, axis=-1),
            ],
            axis=-1,
        )

    return residual
