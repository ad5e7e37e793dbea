"""The adaptive plan's steering estimate: the BRDF its second pass is placed for, made
from the survey's samples (docs/explanations/adaptive.md).

``extend(survey_plan, estimate(measured, options.model))`` (`gonio.planner.two_pass`)
plans the second pass; the planner sees only the estimate, a function of the direction
pairs, never the reconstruction that made it.
"""

from __future__ import annotations

from gonio.analysis import Measured
from gonio.reconstruct import fit, reconstruct
from gonio.types import BrdfEval

#: The ``model`` that steers by the survey's own reconstruction instead of a fit.
SURVEY = "survey"


def estimate(measured: Measured, model: str) -> BrdfEval:
    """The BRDF (sr⁻¹) the second pass's density is taken from: the ``model`` family
    (a `gonio fit` spec) fitted to the survey's samples ``measured``, or for ``survey``
    the survey's own rbf reconstruction (no model at all)."""
    if model == SURVEY:
        return reconstruct(measured, method="rbf", extrapolate="nearest").eval
    return fit(measured, model).model.eval
