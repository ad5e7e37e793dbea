"""Starting points of a fit: a fast moment estimate of the lobe, then jittered copies.

The moment estimate reads the data once: the diffuse level is a low percentile of f
(`FLOOR_PERCENTILE`); the squared excess e² (e = f − floor; squared so that the peak
outweighs the heavy tails of GGX) weights the slopes of the halfway vector. For a
Beckmann lobe D² ∝ exp(−2 tan² θh/α²): ⟨tan² θh⟩ = α²/2, per axis ⟨s_x²⟩ = α_x²/4;
for a cosine power cos^2n x ≈ exp(−n x²): ⟨x²⟩ = 1/n, with x = θh, or the angle ψ to
the mirror direction for Phong. A family's k-th lobe starts 3^k times broader. Given
the shapes, the weights (albedo, ks, f0) are the non-negative least-squares scales of
each term at weight 1, per channel. Later starts multiply the shape parameters by
log-normal factors (σ = `JITTER` in log) and solve the weights again. Parameters with
no estimate start at `gonio.brdf.family.TYPICAL`.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from gonio.analysis import Measured
from gonio.brdf import Family, Slot, pair
from gonio.types import FloatArray

#: Percentile of f taken as the diffuse level.
FLOOR_PERCENTILE = 20.0
#: Weights set by the linear solve, and the value each term is evaluated at for it.
WEIGHTS = ("albedo", "ks", "f0")
#: Spread (natural log) of the shape parameters of the jittered starts.
JITTER = 0.5
#: Broadening of each further lobe of a family.
LOBE_STEP = 3.0


def starts(
    family: Family, slots: tuple[Slot, ...], measured: Measured, *, count: int, seed: int
) -> list[FloatArray]:
    """``count`` starting vectors: the moment estimate first."""
    f = measured.f.reshape(len(measured), -1)
    shapes = _moments(measured, f)
    x0 = np.array(family.typical(slots), dtype=np.float64)
    lobes = np.cumsum([any(p not in WEIGHTS for p in t.free) for t in family.terms]) - 1
    for j, slot in enumerate(slots):
        phong = slot.param == "n" and family.terms[slot.term].model == "phong"
        key = "phong_n" if phong else slot.param
        if key in shapes:
            broad = LOBE_STEP ** max(int(lobes[slot.term]), 0)
            x0[j] = shapes[key] / broad**2 if slot.param == "n" else shapes[key] * broad
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        x = x0.copy()
        if k:
            shape = np.array([s.param not in WEIGHTS and s.channel is None for s in slots])
            x[shape] *= np.exp(rng.normal(0.0, JITTER, int(shape.sum())))
        low = np.array([s.low for s in slots])
        high = np.array([s.high for s in slots])
        out.append(_weights(family, slots, measured, f, np.clip(x, low, high)))
    return out


def _moments(measured: Measured, f: FloatArray) -> dict[str, float]:
    """Shape estimates from the excess over the diffuse floor (module docstring)."""
    y = f.mean(axis=1)
    excess = np.maximum(y - np.percentile(y, FLOOR_PERCENTILE), 0.0) ** 2
    total = float(excess.sum())
    if total <= 0.0:
        return {}
    p = pair(measured.wi, measured.wo)
    hx, hy, hz = p.halfway()
    hz = np.maximum(hz, 1e-3 * np.maximum(np.abs(hx), np.abs(hy)) + 1e-12)
    sx2 = float(excess @ (hx / hz) ** 2) / total
    sy2 = float(excess @ (hy / hz) ** 2) / total
    psi2 = float(excess @ (2.0 * (1.0 - p.cos_psi()))) / total
    tan2 = sx2 + sy2
    return {
        "alpha": float(np.sqrt(2.0 * tan2)),
        "alpha_x": float(2.0 * np.sqrt(sx2)),
        "alpha_y": float(2.0 * np.sqrt(sy2)),
        "n": 1.0 / max(tan2, 1e-12),
        "phong_n": 1.0 / max(psi2, 1e-12),
    }


def _weights(
    family: Family, slots: tuple[Slot, ...], measured: Measured, f: FloatArray, x: FloatArray
) -> FloatArray:
    """``x`` with each term's weights set by non-negative least squares, per channel."""
    unit = x.copy()
    weighted = [j for j, s in enumerate(slots) if s.param in WEIGHTS]
    unit[weighted] = 1.0
    rows = len(measured)
    terms = [
        np.asarray(m.eval(measured.wi, measured.wo)).reshape(rows, -1)
        for m in family.term_models(slots, unit)
    ]
    out = x.copy()
    for c in range(f.shape[1]):
        basis = np.stack([np.broadcast_to(t, f.shape)[:, c] for t in terms], axis=1)
        peak = float(np.max(np.abs(f[:, c])))
        if not peak > 0.0:  # a black channel: nothing to scale to
            continue
        scale = np.maximum(np.abs(f[:, c]), 1e-6 * peak)  # relative residuals, bounded
        try:
            coef, _ = nnls(basis / scale[:, None], f[:, c] / scale)
        except RuntimeError:  # no convergence: keep the current weights
            continue
        for j in weighted:
            slot = slots[j]
            if slot.channel in (None, c):
                out[j] = np.clip(coef[slot.term], slot.low, slot.high)
    return out
