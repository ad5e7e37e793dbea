"""BRDF parametrizations: direction pairs ↔ four coordinates, vectorized.

``get(name)`` returns a :class:`Parametrization` with ``names``, ``bounds``,
``forward(wi, wo)``, ``inverse(coords)``, ``valid(coords)`` and the isotropic
reduction ``forward_iso`` / ``inverse_iso`` / ``valid_iso``; ``names()`` lists them.
Conventions: z is the normal, unit directions point away from the surface, ``wi``
toward the light, radians, azimuths in [0, 2π). See docs/explanations/parametrizations.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gonio.errors import UnknownNameError
from gonio.faces import lazy_face
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


if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.params import cases as cases
    from gonio.params.cases import NAMED_PAIRS as NAMED_PAIRS
    from gonio.params.cases import direction as direction
    from gonio.params.cases import roundtrip_error as roundtrip_error
    from gonio.params.conditioning import condition_number as condition_number
    from gonio.params.conditioning import pair_frame as pair_frame
    from gonio.params.conditioning import singular_values as singular_values
    from gonio.params.conditioning import tangent_jacobian as tangent_jacobian
    from gonio.params.spherical import polar as polar

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "NAMED_PAIRS": "cases",
    "cases": "cases",
    "condition_number": "conditioning",
    "direction": "cases",
    "pair_frame": "conditioning",
    "polar": "spherical",
    "roundtrip_error": "cases",
    "singular_values": "conditioning",
    "tangent_jacobian": "conditioning",
}
__all__ = ["DOMAIN_TOLERANCE", "Parametrization", "get", "names", *WHERE]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
