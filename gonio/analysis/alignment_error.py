"""What the uncertainty of the rig's measured alignment adds to each calibrated sample's
σ: the alignment file states the fitted parameters' covariance, which moves each
measured direction (`gonio.rig.sensitivity.alignment_covariance`), which moves f by
its slope there, to first order: σ_align = √(∇f Σ_ω ∇fᵀ)
(`gonio.rig.sensitivity.alignment_brdf_sigma`). The slope is that of the BRDF the run's
own samples suggest (`gonio.analysis.estimate`, in log f), at the read-back angles: on
the glossy metal at 300 samples within 0.8–1.13 of the true BRDF's for 80 % of them;
where the slope is tiny (a matte sample, 0.04 % of f per 0.5°) the noise's own ripple
widens that to 0.8–2. It adds in
quadrature to the radiometric σ: the two are independent.

Applies where the rig's alignment file has a fit record (an alignment set by hand
states no uncertainty, and a rig without one none to propagate); nothing is added for a
run with too few distinct pairs to estimate a slope from.
"""

from __future__ import annotations

import numpy as np

from gonio.analysis.estimate import Estimate
from gonio.rig import alignment_brdf_sigma, stated_covariance
from gonio.store import Run
from gonio.types import BoolArray, FloatArray


def alignment_error(run: Run, f: FloatArray) -> FloatArray:
    """σ_align (N,) (sr⁻¹) of each of the run's calibrated values ``f`` (N,); 0 where
    it does not apply (the module) and where f is not finite."""
    rig = run.plan.rig
    out = np.zeros(len(f))
    usable: BoolArray = np.isfinite(f)
    if not np.any(stated_covariance(rig)) or not np.any(usable):
        return out
    wi, wo = run.directions()
    model = Estimate(wi[usable], wo[usable], f[usable], isotropic=run.plan.spec.isotropic, log=True)
    if not model.usable:
        return out
    out[usable] = alignment_brdf_sigma(model, rig, run.angles()[usable])
    return out


def with_alignment_error(run: Run, f: FloatArray, sigma: FloatArray) -> FloatArray:
    """``sigma`` (N,) with `alignment_error` added in quadrature."""
    return np.asarray(np.hypot(sigma, alignment_error(run, f)), dtype=np.float64)
