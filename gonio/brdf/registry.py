"""Model names → constructors: `create` and `names`.

``create(name, **params)`` checks the parameter names against the model's
signature, so a typo or a missing required parameter is a `DomainError` with the
accepted names, never a bare ``TypeError``. A model made of models (the sum) takes a
keyword ``factory``: `create` passes itself, the user never does.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable

from gonio.brdf.base import BRDF
from gonio.errors import DomainError, UnknownNameError

#: Model name → (module of `gonio.brdf`, class): a model's module is imported when the
#: model is first asked for, so naming the models loads none of them (the microfacet
#: models load scipy.special, the measured tables scipy.ndimage).
_MODELS: dict[str, tuple[str, str]] = {
    "lambert": ("models", "Lambert"),
    "phong": ("models", "Phong"),
    "blinn_phong": ("models", "BlinnPhong"),
    "cosine_quadratic": ("models", "CosineQuadratic"),
    "cosine_quadratic_modified": ("models", "CosineQuadraticModified"),
    "schlick_lobe": ("models", "SchlickLobe"),
    "cook_torrance": ("cook_torrance", "CookTorrance"),
    "ggx_anisotropic": ("cook_torrance", "GGXAnisotropic"),
    "fresnel_test_function": ("characteristic", "FresnelTestFunction"),
    "specular_test_function": ("characteristic", "SpecularTestFunction"),
    "grazing_test_function": ("characteristic", "GrazingTestFunction"),
    "merl": ("merl", "MerlTable"),
    "utia": ("utia", "UtiaTable"),
    "rgl": ("rgl", "RglTable"),
    "factored": ("factored", "Factored"),
    "sum": ("composite", "Sum"),
}


def names() -> list[str]:
    """The registered model names."""
    return list(_MODELS)


def model_class(name: str) -> type[BRDF]:
    """The class registered as ``name`` (its module imported on first use)."""
    try:
        module, cls = _MODELS[name]
    except KeyError:
        raise UnknownNameError(
            f"unknown BRDF model {name!r}; expected one of {', '.join(_MODELS)}"
        ) from None
    found: type[BRDF] = getattr(importlib.import_module(f"gonio.brdf.{module}"), cls)
    return found


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
