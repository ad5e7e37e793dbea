"""A sum of models: f = Σ f_k, e.g. a Lambertian base under one or two specular lobes.

``create("sum", components=[{"name": "lambert", "albedo": 0.3}, {"name":
"cook_torrance", "alpha": 0.2, "f0": 0.04}])``: each component is a model's name with
its parameters (as a scene's ``material:`` writes one), or a `BRDF` already made. A
named component is made by the ``factory`` the sum receives (`gonio.brdf.create` passes
itself: the registry lists the sum, the sum does not import the registry). The sum is
RGB when any component is (grey components then apply to every channel), reciprocal
(every registered model is), isotropic when all components are, and physically based
when its components are and their albedos add up to at most 1 at every incidence
(`gonio.brdf.material` checks the bound at normal incidence, channel by channel; two
Fresnel lobes each tend to albedo 1 at grazing, so their sum exceeds it there).
``params["components"]`` holds each component's name and parameters, so the sum is
written back as it was given.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from gonio.brdf.base import BRDF
from gonio.brdf.geometry import Pair
from gonio.errors import DomainError, GonioError
from gonio.types import FloatArray

#: Makes a model from its name and keyword parameters: ``factory(name, **params)``.
Factory = Callable[..., BRDF]


def spec_of(model: BRDF) -> dict[str, Any]:
    """A model as a material mapping: ``{"name": …, **params}`` (RGB as lists)."""
    out: dict[str, Any] = {"name": model.name}
    for key, value in model.params.items():
        if key == "components" and isinstance(model, Sum):
            out[key] = [spec_of(c) for c in model.components]
        else:
            out[key] = list(value) if isinstance(value, tuple) else value
    return out


class Sum(BRDF):
    """f = Σ f_k over ``components`` (at least one; see the module docstring); ``factory``
    makes the components given by name (`gonio.brdf.create`)."""

    name = "sum"
    physically_based = True  # as its components, when their albedos add up to ≤ 1

    def __init__(self, components: object, *, factory: Factory | None = None) -> None:
        if isinstance(components, str | bytes) or not isinstance(components, Sequence):
            raise DomainError(f"parameter components must be a list of models, got {components!r}")
        if not components:
            raise DomainError("parameter components must name at least one model")
        self.components: tuple[BRDF, ...] = tuple(
            _component(j, c, factory) for j, c in enumerate(components)
        )
        super().__init__({})
        self.params["components"] = tuple(spec_of(c) for c in self.components)  # type: ignore[assignment]
        self.is_rgb = any(c.is_rgb for c in self.components)

    @property
    def isotropic(self) -> bool:
        return all(c.isotropic for c in self.components)

    def _eval(self, p: Pair) -> FloatArray:
        total: FloatArray = np.zeros(p.shape + ((3,) if self.is_rgb else ()))
        for c in self.components:
            value = np.asarray(c._eval(p), dtype=np.float64)
            total = total + (value[..., None] if self.is_rgb and not c.is_rgb else value)
        return total


def _component(index: int, given: object, factory: Factory | None) -> BRDF:
    """A component: a `BRDF`, or a mapping with ``name`` and the model's parameters
    (made by ``factory``)."""
    if isinstance(given, BRDF):
        return given
    if not isinstance(given, Mapping) or not isinstance(given.get("name"), str):
        raise DomainError(
            f"components[{index}]: expected a model's name and parameters, got {given!r}"
        )
    if factory is None:
        raise DomainError(f"components[{index}]: a model given by name needs a factory")
    params = {k: v for k, v in given.items() if k != "name"}
    try:
        return factory(given["name"], **params)
    except GonioError as exc:
        raise DomainError(f"components[{index}]: {exc}") from None
