"""Whether an adaptive plan's second pass adapts: decided from its survey, by the error
model that places it (docs/explanations/adaptive.md, "When the plan adapts").

Of a plan of n kept targets, the survey's n_s are uniform (density u over the cells the
rig reaches) and the second pass's n − n_s follow a density p (`gonio.planner.adaptive`,
a share ``floor`` of it uniform), so the plan's density is ρ = s·u + (1 − s)·p,
s = n_s/n. The error model that shapes p says the squared error in a cell of test
measure w and indicator e goes as w·e²·ρ^(−4/d); against a uniform plan of as many
samples (ρ = u) the estimate ``f`` predicts the ratio of squared errors

    A(ρ) = Σ w e² (ρ/u)^(−k) / Σ w e²,   k = 4/d.

That ratio is only as good as the estimate. With r the RMS difference between
log(1 + f̂) and log(1 + f) at the survey's pairs (the metric's scale) and σ the survey's
standard deviation of log(1 + f), q = min(1, r²/σ²) is the share of the survey's
variation the estimate does not explain. Where that part's error sits is unknown, so the
density is given no credit for it: it keeps the share q it has under a uniform plan.
The predicted ratio of squared errors, adaptive over uniform, is

    R = (1 − q)·A(ρ) + q,

and the predicted gain in log-RMSE G = R^(−1/2) (at most A^(−1/2), at least 1 when
A ≤ 1). The second pass follows the density if G ≥ `MARGIN`; otherwise it is uniform
outright: the survey's own Sobol sequence continued, so that the whole plan is the
uniform Sobol plan of its seed (`gonio.planner.two_pass`).

`MARGIN` is well above 1 because the model overrates what a plan reconstructed by rbf
gains, the more so the rougher the lobe: studies/adaptive.py prints G beside the
measured gain and beside what a plan forced to adapt gives (docs/results/adaptive.md).
On rough conductors with no diffuse part, where uniform Rusinkiewicz is already close
to the best density and the rbf's error does not follow the curvature law, a predicted
1.3–1.8× came out between 0.41× and 1.31×; every plan there that adapted at G ≥ 1.9
gained (1.08–3.82×). A wrong guess toward adapting costs more than one toward
uniform: uniform is the plan the user would otherwise have measured. Two variants were
measured and left out: charging the unexplained part as a flat error (which any
non-uniform density makes worse, by Jensen's inequality, the more so the smaller the
survey's share) fell back on the glossy gold scene at large counts, whose unexplained
part (a Beckmann fit's tails against GGX's) sits by the lobe where the density is high;
and a raised floor (a mix toward uniform) as a third choice: the model ranks floors by
less than its own error, and a raised floor was never better than both the plan's floor
and uniform.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from gonio.planner.adaptive import ErrorMap
from gonio.types import FloatArray

#: The least predicted gain in log-RMSE over uniform for which the plan adapts.
MARGIN = 1.9

Kind = Literal["adaptive", "uniform"]


@dataclass(frozen=True)
class Choice:
    """How the second pass is placed: ``kind``, the ``floor`` of its density (1 for
    uniform), the predicted ``gain`` G in log-RMSE of the adaptive density over a
    uniform plan, the estimate's predicted gain ``gain_estimate`` (A alone, q = 0) and
    ``unexplained`` (q) of the module docstring, and the ``margin`` G was held to."""

    kind: Kind
    floor: float
    gain: float
    gain_estimate: float
    unexplained: float
    margin: float = MARGIN

    @property
    def reason(self) -> str:
        """Which placement and why, one line (the plan's summary shows it)."""
        why = (
            f"predicted gain over uniform {self.gain:.2f}× in log-RMSE "
            f"({self.gain_estimate:.2f}× by the steering estimate, which leaves "
            f"{self.unexplained:.0%} of the survey's variation in log(1 + f) unexplained)"
        )
        if self.kind == "uniform":
            return f"uniform: the adaptive density's {why} is below {self.margin:g}×"
        return f"adaptive (floor {self.floor:g}): {why}"


def survey_misfit(estimate: FloatArray, measured: FloatArray) -> float:
    """q of the module docstring: the share of the variance of log(1 + f) over the
    survey's samples ``measured`` (N,) or (N, C) that the estimate's values there
    ``estimate`` (same shape, sr⁻¹) leave unexplained, in [0, 1]."""
    g = np.log1p(np.maximum(_grey(measured), 0.0))
    h = np.log1p(np.maximum(_grey(estimate), 0.0))
    residual = float(np.mean((h - g) ** 2))
    spread = float(np.var(g))
    if spread <= 0.0:
        return 0.0 if residual <= 0.0 else 1.0
    return min(1.0, residual / spread)


def _grey(values: FloatArray) -> FloatArray:
    v = np.asarray(values, dtype=np.float64)
    return np.asarray(v.mean(axis=1) if v.ndim == 2 else v, dtype=np.float64)


def predicted_ratio(errors: ErrorMap, p: FloatArray, survey_share: float) -> float:
    """A of the module docstring for a second-pass density ``p`` (cells,) after a survey
    holding ``survey_share`` of the plan's samples (1 where the indicator is zero)."""
    u = errors.uniform
    reached = u > 0
    rho = survey_share * u + (1.0 - survey_share) * p
    k = 4.0 / len(errors.shape)
    scale = np.power(np.where(reached, rho, 1.0) / np.where(reached, u, 1.0), -k)
    weight = np.where(reached, errors.w, 0.0) * errors.e**2
    return float(np.sum(weight * scale) / weight.sum()) if weight.sum() > 0 else 1.0


def choose(
    errors: ErrorMap,
    unexplained: float,
    survey: int,
    total: int,
    floor: float,
    *,
    margin: float = MARGIN,
) -> Choice:
    """The placement of the second pass (module docstring): ``errors`` of the steering
    estimate, ``unexplained`` = q (`survey_misfit`), ``survey`` of ``total`` kept targets
    measured, the plan's ``floor``; ``margin``: the least G that adapts (0: always, for
    studies of what adapting would give)."""
    a = predicted_ratio(errors, errors.density(floor).p, survey / total)
    gain = 1.0 / math.sqrt((1.0 - unexplained) * a + unexplained)
    kind: Kind = "adaptive" if gain >= margin else "uniform"
    floor = floor if kind == "adaptive" else 1.0
    return Choice(kind, floor, gain, 1.0 / math.sqrt(a), unexplained, margin)
