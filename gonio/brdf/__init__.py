"""Analytic BRDF models, vectorized over direction pairs.

``create(name, **params)`` returns a `BRDF` with ``name``, ``params``,
``eval(wi, wo)`` (sr⁻¹, cosine factor excluded), ``is_rgb`` and the flags
``reciprocal``, ``isotropic``, ``physically_based``; ``names()`` lists the models.
Directions are unit vectors (..., 3) in the sample frame (z = normal), pointing
away from the surface, ``wi`` toward the light and ``wo`` toward the detector.
See docs/explanations/brdf.md for formulas, normalizations and measurements.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gonio.brdf.base import BRDF
from gonio.brdf.registry import create, names
from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.brdf import factored_file as factored_file
    from gonio.brdf import family as family
    from gonio.brdf import lobe_errors as lobe_errors
    from gonio.brdf import lobes as lobes
    from gonio.brdf import merl as merl
    from gonio.brdf import microfacet as microfacet
    from gonio.brdf import rgl as rgl
    from gonio.brdf import tensor_file as tensor_file
    from gonio.brdf import utia as utia
    from gonio.brdf.base import LOG_FLOOR as LOG_FLOOR
    from gonio.brdf.composite import spec_of as spec_of
    from gonio.brdf.family import Family as Family
    from gonio.brdf.family import Slot as Slot
    from gonio.brdf.family import parse as parse
    from gonio.brdf.geometry import pair as pair
    from gonio.brdf.lobe_errors import K_PRINTED as K_PRINTED
    from gonio.brdf.lobe_errors import Lobe as Lobe
    from gonio.brdf.marginal import Marginal2D as Marginal2D
    from gonio.brdf.marginal import Table as Table
    from gonio.brdf.material import MaterialError as MaterialError
    from gonio.brdf.material import MaterialSpec as MaterialSpec
    from gonio.brdf.material import build as build
    from gonio.brdf.material import material_schema as material_schema
    from gonio.brdf.models import blinn_normalization as blinn_normalization
    from gonio.brdf.quadrature import directional_albedo as directional_albedo
    from gonio.brdf.quadrature import legendre as legendre
    from gonio.brdf.rgl import RglTable as RglTable

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Family": "family",
    "K_PRINTED": "lobe_errors",
    "LOG_FLOOR": "base",
    "Lobe": "lobe_errors",
    "Marginal2D": "marginal",
    "MaterialError": "material",
    "MaterialSpec": "material",
    "RglTable": "rgl",
    "Slot": "family",
    "Table": "marginal",
    "blinn_normalization": "models",
    "build": "material",
    "directional_albedo": "quadrature",
    "legendre": "quadrature",
    "factored_file": "factored_file",
    "family": "family",
    "lobe_errors": "lobe_errors",
    "lobes": "lobes",
    "material_schema": "material",
    "merl": "merl",
    "microfacet": "microfacet",
    "pair": "geometry",
    "parse": "family",
    "rgl": "rgl",
    "spec_of": "composite",
    "tensor_file": "tensor_file",
    "utia": "utia",
}
__all__ = ["BRDF", "create", "names", *WHERE]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
