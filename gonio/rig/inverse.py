"""Closed-form inverse kinematics of the shipped rig types.

Each function takes sample-frame directions ``wi``, ``wo`` (N, 3) and returns every
joint-angle solution, {axis name: (K, N)} with the same K candidates for all pairs
(before limits are applied), candidate-major: each candidate's angles for all pairs
are one contiguous row, so that the limits, keep-out boxes and travel times of
`gonio.rig.model` run over long rows (on pairs × K × axes with the axes last, every
numpy call loops over 4 values at a time, tens of times slower per value).
Conventions (the rig files use them; `gonio.rig.model` checks the chains):

arch
    light_elevation θL about lab y: d_L = R_y(θL) z = (sin θL, 0, cos θL);
    detector_azimuth φD about lab z then detector_elevation θD about the turned y:
    d_D = R_z(φD) R_y(θD) z; sample_rotation ψ about the normal: R_sample = R_z(ψ).
    With d = R_sample ω: ψ = −φi (θL = θi) or π − φi (θL = −θi); then θD = ±θo with
    φD = φo + ψ (+ π for the negative elevation). K = 4.
in_plane
    light_arm a and detector_arm b about lab y, both in the lab x-z plane;
    sample_tilt τ about lab x then sample_rotation ψ about the normal:
    R_sample = R_x(τ) R_z(ψ). The plane of ωi and ωo must be turned into the x-z plane:
    its normal m = ωi × ωo goes to +y. R_z(ψ) m has no x part for ψ = atan2(mx, my);
    then τ = atan2(−m'z, m'y); the arms are the angles of R_sample ω in the x-z plane.
    The second solution uses −m. When ωi ∥ ωo any plane through them works: the one
    through the normal (τ = 0) is used. K = 2.

Azimuth-like angles come out in (−π, π]; `gonio.rig.model` wraps them into each
axis's range.
"""

from __future__ import annotations

import numpy as np

from gonio.types import FloatArray

Solutions = dict[str, FloatArray]


def _polar(w: FloatArray) -> tuple[FloatArray, FloatArray]:
    r = np.hypot(w[:, 0], w[:, 1])
    return np.arctan2(r, w[:, 2]), np.arctan2(w[:, 1] + 0.0, w[:, 0] + 0.0)


def _wrap(angle: FloatArray) -> FloatArray:
    """Angles to (−π, π]."""
    return np.asarray(np.pi - np.mod(np.pi - angle, 2.0 * np.pi), dtype=np.float64)


def arch(wi: FloatArray, wo: FloatArray) -> Solutions:
    ti, pi_ = _polar(wi)
    to, po = _polar(wo)
    psi = np.stack([-pi_, np.pi - pi_, -pi_, np.pi - pi_])
    light = np.stack([ti, -ti, ti, -ti])
    elevation = np.stack([to, to, -to, -to])
    azimuth = po + psi + np.array([0.0, 0.0, np.pi, np.pi])[:, None]
    wrapped = _wrap(psi[:2])  # the last two solutions turn the sample as the first two
    return {
        "light_elevation": light,
        "detector_azimuth": _wrap(azimuth),
        "detector_elevation": elevation,
        "sample_rotation": np.concatenate([wrapped, wrapped]),
    }


def in_plane(wi: FloatArray, wo: FloatArray) -> Solutions:
    # m = ωi × ωo, computed as ωi × (ωo ∓ ωi) (the same in exact arithmetic): near
    # retro-reflection (or opposite directions) ωi × ωo loses its relative precision
    # (m off by ~ε/|ωi × ωo|, 4e-5 rad at a separation of 1e-12), the small difference
    # does not.
    same_side = np.einsum("ij,ij->i", wi, wo) >= 0.0
    m = np.cross(wi, np.where(same_side[:, None], wo - wi, wo + wi))
    norm = np.linalg.norm(m, axis=1)
    # ωi ∥ ωo (retro-reflection, or opposite directions on the horizon): the plane
    # through the normal and ωi, whose normal is horizontal (then τ = 0).
    parallel = norm < 1e-12
    if np.any(parallel):
        fallback = np.cross(np.array([0.0, 0.0, 1.0]), wi[parallel])
        flat = np.linalg.norm(fallback, axis=1) < 1e-12  # ωi = n as well: any horizontal
        fallback[flat] = [0.0, 1.0, 0.0]
        m[parallel] = fallback
        norm = np.linalg.norm(m, axis=1)
    m = m / norm[:, None]
    out: dict[str, list[FloatArray]] = {
        k: [] for k in ("light_arm", "detector_arm", "sample_tilt", "sample_rotation")
    }
    for sign in (1.0, -1.0):
        ms = sign * m
        psi = np.arctan2(ms[:, 0], ms[:, 1])
        c, s = np.cos(psi), np.sin(psi)
        my = s * ms[:, 0] + c * ms[:, 1]  # R_z(ψ) m has x = 0, y = my ≥ 0
        tau = np.arctan2(-ms[:, 2], my)
        for name, w in (("light_arm", wi), ("detector_arm", wo)):
            x = c * w[:, 0] - s * w[:, 1]
            y = s * w[:, 0] + c * w[:, 1]
            # R_x(τ): z' = sin τ · y + cos τ · z (x unchanged)
            z = np.sin(tau) * y + np.cos(tau) * w[:, 2]
            out[name].append(np.arctan2(x, z))
        out["sample_tilt"].append(tau)
        out["sample_rotation"].append(psi)
    return {k: np.stack(v) for k, v in out.items()}


SOLVERS = {"arch": arch, "in_plane": in_plane}
