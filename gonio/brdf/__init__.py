"""Analytic BRDF models, vectorized over direction pairs.

``create(name, **params)`` returns a `BRDF` with ``name``, ``params``,
``eval(wi, wo)`` (sr⁻¹, cosine factor excluded), ``is_rgb`` and the flags
``reciprocal``, ``isotropic``, ``physically_based``; ``names()`` lists the models.
Directions are unit vectors (..., 3) in the sample frame (z = normal), pointing
away from the surface, ``wi`` toward the light and ``wo`` toward the detector.
See docs/explanations/brdf.md for formulas, normalizations and measurements.
"""

from __future__ import annotations

from gonio.brdf.base import BRDF
from gonio.brdf.registry import create, names

__all__ = ["BRDF", "create", "names"]
