"""Physical constraints of a rig, as vectorized tests on direction pairs and joint angles.

Footprint (sample plane, sample frame): a collimated beam of diameter D arriving from
ωi lights an ellipse with semi-axes D / (2 cos θi) along ωi's azimuth and D/2 across;
the detector, whose field of view is a circle of diameter F seen from ωo, sees an
ellipse F / (2 cos θo) × F/2 along ωo's azimuth. A pair is usable when the lit ellipse
lies inside the sample (a disc of diameter S: D / cos θi ≤ S) and inside the seen
ellipse (the detector collects all the reflected light). Containment of two centred
ellipses with shape matrices Q = A² u uᵀ + B² v vᵀ: E₁ ⊂ E₂ ⟺ λmax(Q₂⁻¹ Q₁) ≤ 1, in
closed form for 2 × 2.

View (a point source): a lamp lights the whole sample plane from above, whatever its
distance, so nothing confines the lit area; what the detector sees must then lie on
the sample, or it measures the holder around it. The seen ellipse's long axis F / cos θo
is its widest extent: the view is on the sample disc ⟺ F ≤ S cos θo.
"""

from __future__ import annotations

import numpy as np

from gonio.types import BoolArray, FloatArray

#: cos θ below which a footprint counts as unbounded (θ within 1e-9 rad of 90°).
_COS_FLOOR = 1e-9


def separation(wi: FloatArray, wo: FloatArray) -> FloatArray:
    """The angle between ωi and ωo (rad), accurate near 0 and π."""
    return np.asarray(
        2.0 * np.arctan2(np.linalg.norm(wi - wo, axis=-1), np.linalg.norm(wi + wo, axis=-1)),
        dtype=np.float64,
    )


def footprint_ok(
    wi: FloatArray, wo: FloatArray, beam_mm: float, sample_mm: float, fov_mm: float
) -> BoolArray:
    """True where the lit ellipse fits the sample and the detector's view (see module)."""
    ci = np.maximum(wi[..., 2], _COS_FLOOR)
    co = np.maximum(wo[..., 2], _COS_FLOOR)
    a1, b1 = 0.5 * beam_mm / ci, 0.5 * beam_mm
    a2, b2 = 0.5 * fov_mm / co, 0.5 * fov_mm
    # cos² of the angle between the two azimuths (1 where an azimuth is undefined: the
    # ellipse is then a circle and the angle does not matter).
    ri = np.hypot(wi[..., 0], wi[..., 1])
    ro = np.hypot(wo[..., 0], wo[..., 1])
    dot = wi[..., 0] * wo[..., 0] + wi[..., 1] * wo[..., 1]
    denom = ri * ro
    c2 = np.where(denom > 0.0, (dot / np.where(denom > 0.0, denom, 1.0)) ** 2, 1.0)
    s2 = 1.0 - c2
    trace = a1**2 * (c2 / a2**2 + s2 / b2**2) + b1**2 * (s2 / a2**2 + c2 / b2**2)
    det = (a1 * b1) ** 2 / (a2 * b2) ** 2
    lam = 0.5 * (trace + np.sqrt(np.maximum(trace**2 - 4.0 * det, 0.0)))
    return np.asarray((2.0 * a1 <= sample_mm) & (lam <= 1.0 + 1e-12), dtype=np.bool_)


def view_on_sample(wo: FloatArray, fov_mm: float, sample_mm: float) -> BoolArray:
    """True where the detector's seen ellipse (F / cos θo × F, centred) lies on the
    sample disc of diameter S: F ≤ S cos θo (see module)."""
    return np.asarray(fov_mm <= sample_mm * wo[..., 2], dtype=np.bool_)


def in_box(angles: FloatArray, ranges: dict[int, tuple[float, float]]) -> BoolArray:
    """True where every listed joint (column index → [lo, hi] rad) is inside its range."""
    inside = np.ones(angles.shape[:-1], dtype=np.bool_)
    for column, (lo, hi) in ranges.items():
        inside &= (angles[..., column] >= lo) & (angles[..., column] <= hi)
    return inside
