"""BRDF parametrizations: direction pairs ↔ four coordinates, vectorized.

``get(name)`` returns a :class:`Parametrization` with ``names``, ``bounds``,
``forward(wi, wo)``, ``inverse(coords)``, ``valid(coords)`` and the isotropic
reduction ``forward_iso`` / ``inverse_iso`` / ``valid_iso``; ``names()`` lists them.
Conventions: z is the normal, unit directions point away from the surface, ``wi``
toward the light, radians, azimuths in [0, 2π). See docs/explanations/parametrizations.md.
"""

from __future__ import annotations

from gonio.errors import UnknownNameError
from gonio.params.base import DOMAIN_TOLERANCE, Parametrization
from gonio.params.hybrid import Hybrid
from gonio.params.orthographic import Orthographic
from gonio.params.rusinkiewicz import Rusinkiewicz
from gonio.params.spherical import Spherical

_REGISTRY: dict[str, Parametrization] = {
    p.name: p for p in (Spherical(), Rusinkiewicz(), Orthographic(), Hybrid())
}


def names() -> list[str]:
    """The registered parametrization names."""
    return list(_REGISTRY)


def get(name: str) -> Parametrization:
    """The parametrization called ``name`` (see `names`)."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise UnknownNameError(
            f"unknown parametrization {name!r}; expected one of {', '.join(_REGISTRY)}"
        ) from None


__all__ = ["DOMAIN_TOLERANCE", "Parametrization", "get", "names"]
