"""Weighted least-squares fits of a model family to measured BRDF samples
(docs/explanations/fitting.md).

The residual of sample i (channel c in an RGB fit) is r = (f_model − f)/σ, σ the
sample's 1σ uncertainty. A σ of 0 says no estimate (a detector that averages on its
own reports no spread), not an exact value: it is replaced by the median positive σ of
its channel; a positive σ is raised to at least `SIGMA_FLOOR` × that median (a sample
claiming near-exactness would otherwise own the fit). A run whose every σ is 0 is
fitted unweighted (σ = 1: χ² is then only a scale).
`scipy.optimize.least_squares` (trust-region reflective, bounded) runs from several
starts (`gonio.reconstruct.starts`) and keeps the lowest χ²; its Jacobian is by forward
differences, the channels of a colour parameter stepped at once (`_jacobian`).

Uncertainty: cov = (JᵀJ)⁻¹ · χ²_red with J the Jacobian of r at the optimum and
χ²_red = χ²/(M − P) (M residuals, P free parameters), plus the error the values share
through the run's reference readings (`gonio.analysis.shared`): reading k of
channel c, of relative 1σ u_k, moves the parameters by g_k = J⁺ (w_k f/σ)|_c per unit
relative error, so cov += Σ u_k² g_k g_kᵀ. (σ already holds each sample's share as if
it were its own; counting it twice keeps the errors on the safe side.) Standard errors
are √diag(cov).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from gonio.analysis import Measured, SharedError
from gonio.brdf import BRDF, Family, Slot, parse, spec_of
from gonio.errors import GonioError
from gonio.reconstruct import regions as pair_regions
from gonio.reconstruct.starts import starts as make_starts
from gonio.types import FloatArray

#: A positive σ below this fraction of its channel's median positive σ is raised to it.
SIGMA_FLOOR = 1e-3
#: Starts tried by default (the moment estimate and jittered copies of it).
STARTS = 4


@dataclass(frozen=True)
class RegionResidual:
    """The weighted residuals of one region: count of samples, χ² per residual and
    mean residual (a bias shows as |mean| ≫ 1/√count)."""

    count: int
    chi2: float
    mean: float


@dataclass(frozen=True)
class FitResult:
    """A fitted family. ``names``, ``values``, ``stderr`` and ``covariance`` follow the
    fitted vector (``label.param`` or ``label.param[r]``)."""

    spec: str
    model: BRDF
    names: tuple[str, ...]
    values: FloatArray
    stderr: FloatArray
    covariance: FloatArray
    chi2: float
    dof: int
    chi2_red: float
    regions: dict[str, RegionResidual]
    samples: int
    starts: int
    success: bool

    def params(self) -> dict[str, tuple[float, float]]:
        """name → (value, standard error)."""
        pairs = zip(self.names, self.values, self.stderr, strict=True)
        return {n: (float(v), float(s)) for n, v, s in pairs}

    def material(self) -> dict[str, Any]:
        """The fitted model as a scene's ``material:`` mapping."""
        return spec_of(self.model)

    def figures(self) -> dict[str, Any]:
        """Everything as JSON-ready values."""
        return {
            "model": self.spec,
            "samples": self.samples,
            "chi2": self.chi2,
            "dof": self.dof,
            "chi2_red": self.chi2_red,
            "success": self.success,
            "starts": self.starts,
            "params": {n: {"value": v, "stderr": s} for n, (v, s) in self.params().items()},
            "regions": {k: vars(r) for k, r in self.regions.items()},
            "material": self.material(),
        }


def fit(
    measured: Measured,
    spec: str | Family,
    *,
    starts: int = STARTS,
    seed: int = 0,
    shared: SharedError | Sequence[SharedError] | None = None,
) -> FitResult:
    """Fit the family ``spec`` (a SPEC string or a parsed `Family`) to ``measured``.

    ``starts``: starting points tried (the moment estimate, then jittered copies drawn
    from ``seed``). ``shared``: the errors the samples share through their calibration
    (`gonio.analysis.shared.shared_error` of the run; one per channel in an RGB
    fit), None to leave them out. `GonioError` (one line) when there are no more
    residuals than free parameters or no start gives a finite fit."""
    family = spec if isinstance(spec, Family) else parse(spec)
    rgb = measured.is_rgb
    slots = family.slots(rgb)
    f = measured.f.reshape(len(measured), -1)
    sigma = _floored(measured.sigma.reshape(f.shape))
    m, p = f.size, len(slots)
    if m <= p:
        raise GonioError(
            f"{measured.source}: {len(measured)} samples cannot fit {p} free parameters"
        )
    low = np.array([s.low for s in slots])
    high = np.array([s.high for s in slots])

    last: list[tuple[FloatArray, FloatArray]] = []

    def residuals(x: FloatArray) -> FloatArray:
        value = family.model(slots, x).eval(measured.wi, measured.wo).reshape(f.shape)
        r = np.asarray(((value - f) / sigma).ravel(), dtype=np.float64)
        last[:] = [(np.array(x, dtype=np.float64), r)]
        return r

    def jacobian(x: FloatArray) -> FloatArray:
        seen = last[0] if last and np.array_equal(last[0][0], x) else None
        r = seen[1] if seen else residuals(x)
        return _jacobian(residuals, x, r, slots, low, high, f.shape[1])

    best = None
    tried = make_starts(family, slots, measured, count=max(starts, 1), seed=seed)
    for x0 in tried:
        result = least_squares(
            residuals,
            np.clip(x0, low, high),
            jac=jacobian,
            bounds=(low, high),
            x_scale="jac",
            method="trf",
        )
        if np.isfinite(result.cost) and (best is None or result.cost < best.cost):
            best = result
    if best is None:
        raise GonioError(f"{measured.source}: model {family.spec!r}: no start gave a finite fit")
    order = family.canonical(slots, best.x)
    x = np.asarray(best.x, dtype=np.float64)[order]
    r = np.asarray(best.fun, dtype=np.float64)
    chi2 = float(r @ r)
    dof = m - p
    jac = np.asarray(best.jac, dtype=np.float64)[:, order]
    cov = _covariance(jac, chi2 / dof, f / sigma, shared)
    return FitResult(
        spec=family.spec,
        model=family.model(slots, x),
        names=tuple(s.name(family.terms) for s in slots),
        values=x,
        stderr=np.sqrt(np.maximum(np.diag(cov), 0.0)),
        covariance=cov,
        chi2=chi2,
        dof=dof,
        chi2_red=chi2 / dof,
        regions=_by_region(measured, r.reshape(f.shape)),
        samples=len(measured),
        starts=len(tried),
        success=bool(best.success),
    )


def _jacobian(
    residuals: Callable[[FloatArray], FloatArray],
    x: FloatArray,
    r: FloatArray,
    slots: tuple[Slot, ...],
    low: FloatArray,
    high: FloatArray,
    channels: int,
) -> FloatArray:
    """The forward-difference Jacobian of ``residuals`` at ``x`` (whose residuals are
    ``r``), with steps √ε·max(1, |x|) turned back or shortened at the bounds (the rule of
    `scipy.optimize.least_squares`' default "2-point"), but the three channels of a
    colour parameter stepped at once: each moves only its own channel's residuals, so
    an RGB fit's Jacobian takes one evaluation per parameter, not per channel, and
    every column is what stepping it alone gives."""
    x = np.asarray(x, dtype=np.float64)
    h = np.finfo(np.float64).eps ** 0.5 * np.where(x >= 0.0, 1.0, -1.0)
    h = h * np.maximum(1.0, np.abs(x))
    below, above = x - low, high - x
    fitting = np.abs(h) <= np.maximum(below, above)
    h = np.where(((x + h < low) | (x + h > high)) & fitting, -h, h)
    h = np.where(~fitting, np.where(above >= below, above, -below), h)
    groups: dict[tuple[int, str] | int, list[int]] = {}
    for i, slot in enumerate(slots):
        groups.setdefault(i if slot.channel is None else (slot.term, slot.param), []).append(i)
    jac = np.zeros((len(r), len(slots)))
    for members in groups.values():
        stepped = x.copy()
        stepped[members] = x[members] + h[members]
        dr = residuals(stepped) - r
        for i in members:
            dx = stepped[i] - x[i]
            c = slots[i].channel
            if c is None:
                jac[:, i] = dr / dx
            else:
                jac[c::channels, i] = dr[c::channels] / dx
    return jac


def _floored(sigma: FloatArray) -> FloatArray:
    """σ with the floor of the module docstring, per channel (columns)."""
    out = np.array(sigma, dtype=np.float64)
    for c in range(out.shape[1]):
        column = out[:, c]
        positive = column[column > 0.0]
        if not positive.size:
            out[:, c] = 1.0
            continue
        typical = float(np.median(positive))
        out[:, c] = np.where(column > 0.0, np.maximum(column, SIGMA_FLOOR * typical), typical)
    return out


def _covariance(
    jac: FloatArray,
    chi2_red: float,
    scaled: FloatArray,
    shared: SharedError | Sequence[SharedError] | None,
) -> FloatArray:
    """(JᵀJ)⁻¹ χ²_red plus the shared calibration errors' part (module docstring);
    ``scaled`` is f/σ, (N, channels)."""
    pinv = np.linalg.pinv(jac)
    cov = np.asarray(pinv @ pinv.T * chi2_red, dtype=np.float64)
    if shared is None:
        return cov
    errors = [shared] if isinstance(shared, SharedError) else list(shared)
    rows, channels = scaled.shape
    if len(errors) != channels or any(len(e) != rows for e in errors):
        raise GonioError(
            f"the calibration errors cover {[len(e) for e in errors]} samples; expected "
            f"{channels} of {rows} (one per channel)"
        )
    for c, error in enumerate(errors):
        design = np.zeros((rows, channels, error.weights.shape[1]))
        design[:, c, :] = scaled[:, c, None] * error.weights
        g = pinv @ design.reshape(rows * channels, -1)  # (P, K)
        cov = cov + (g * error.relative**2) @ g.T
    return cov


def _by_region(measured: Measured, r: FloatArray) -> dict[str, RegionResidual]:
    out = {}
    for name, mask in pair_regions.regions(measured.wi, measured.wo).items():
        part = r[mask]
        count = int(mask.sum())
        out[name] = RegionResidual(
            count=count,
            chi2=float(np.mean(part**2)) if count else 0.0,
            mean=float(np.mean(part)) if count else 0.0,
        )
    return out
