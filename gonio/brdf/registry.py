"""Model names → constructors: `create` and `names`.

``create(name, **params)`` checks the parameter names against the model's
signature, so a typo or a missing required parameter is a `DomainError` with the
accepted names, never a bare ``TypeError``. A model made of models (the sum) takes a
keyword ``factory``: `create` passes itself, the user never does.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

from gonio.brdf.base import BRDF
from gonio.brdf.characteristic import (
    FresnelTestFunction,
    GrazingTestFunction,
    SpecularTestFunction,
)
from gonio.brdf.composite import Sum
from gonio.brdf.cook_torrance import CookTorrance, GGXAnisotropic
from gonio.brdf.factored import Factored
from gonio.brdf.merl import MerlTable
from gonio.brdf.models import (
    BlinnPhong,
    CosineQuadratic,
    CosineQuadraticModified,
    Lambert,
    Phong,
    SchlickLobe,
)
from gonio.brdf.rgl import RglTable
from gonio.brdf.utia import UtiaTable
from gonio.errors import DomainError, UnknownNameError

_MODELS: dict[str, type[BRDF]] = {
    cls.name: cls
    for cls in (
        Lambert,
        Phong,
        BlinnPhong,
        CosineQuadratic,
        CosineQuadraticModified,
        SchlickLobe,
        CookTorrance,
        GGXAnisotropic,
        FresnelTestFunction,
        SpecularTestFunction,
        GrazingTestFunction,
        MerlTable,
        UtiaTable,
        RglTable,
        Factored,
        Sum,
    )
}


def names() -> list[str]:
    """The registered model names."""
    return list(_MODELS)


def model_class(name: str) -> type[BRDF]:
    """The class registered as ``name``."""
    try:
        return _MODELS[name]
    except KeyError:
        raise UnknownNameError(
            f"unknown BRDF model {name!r}; expected one of {', '.join(_MODELS)}"
        ) from None


def create(name: str, **params: object) -> BRDF:
    """The model ``name`` with the given parameters (see each model's docstring)."""
    cls = model_class(name)
    signature = inspect.signature(cls.__init__).parameters
    accepted = [p for p in signature.values() if p.name not in ("self", "factory")]
    known = {p.name for p in accepted}
    unknown = sorted(set(params) - known)
    missing = [p.name for p in accepted if p.default is p.empty and p.name not in params]
    if unknown or missing:
        what = []
        if unknown:
            what.append(f"unknown parameter(s) {', '.join(unknown)}")
        if missing:
            what.append(f"missing parameter(s) {', '.join(missing)}")
        allowed = ", ".join(p.name for p in accepted) or "none"
        raise DomainError(f"{name}: {'; '.join(what)} (accepted: {allowed})")
    make: Callable[..., BRDF] = cls  # subclasses take their own keyword parameters
    if "factory" in signature:
        return make(**params, factory=create)
    return make(**params)
