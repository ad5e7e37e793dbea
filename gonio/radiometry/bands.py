"""How a detector's band sees a BRDF: a grey detector sees an RGB material through the
Rec. 709 luminance weights, a filtered one through a single channel."""

from __future__ import annotations

import numpy as np

from gonio.brdf import BRDF
from gonio.types import BrdfEval

#: Rec. 709 luminance weights: how a grey detector sees an RGB material.
LUMINANCE = (0.2126, 0.7152, 0.0722)


def band_eval(model: BRDF, band: str) -> BrdfEval:
    """f(ωi, ωo) (sr⁻¹) as a detector in ``band`` ("luminance", "r", "g" or "b") sees
    ``model``: one value per pair."""
    if not model.is_rgb:
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    weights = np.asarray(LUMINANCE) if band == "luminance" else np.eye(3)["rgb".index(band)]
    # A sum per pair, not a matrix product: BLAS rounds a product's rows differently
    # with their number, and a pair's value must not depend on its batch.
    return lambda wi, wo: np.asarray((model.eval(wi, wo) * weights).sum(axis=-1), dtype=np.float64)
