"""A material from a configuration file: a `gonio.brdf` model whose parameters are
checked to be physically meaningful, each mistake attributed to the parameter it is
about (`MaterialError.param`).

Reflectances (``albedo``, ``ks``, ``kd``, ``f0``) lie in [0, 1] and the model conserves
energy at normal incidence, channel by channel: ``ks + kd ≤ 1`` for the cosine lobes
(their lobe's albedo is exactly ks there), and ``kd + F(0°) ≤ 1`` for the microfacet
models (their specular albedo is at most the Fresnel reflectance at normal incidence,
as the masking term is at most 1). A ``sum`` (`gonio.brdf.composite`) checks each
component so, and the sum of their bounds (Lambert: its albedo) against 1."""

from __future__ import annotations

import inspect
import re
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ConfigDict, Field, ValidationInfo, model_validator

from gonio.brdf.base import BRDF
from gonio.brdf.composite import Sum
from gonio.brdf.registry import create, model_class, names
from gonio.config import Strict, field_error
from gonio.errors import DomainError, GonioError

#: Parameters that are reflectances, in [0, 1].
REFLECTANCES = ("albedo", "ks", "kd", "f0")
#: The longest message about a parameter (a huge list is not echoed whole).
MAX_MESSAGE = 240


class MaterialError(DomainError):
    """A material that cannot be used; ``param`` names the parameter it is about (None:
    the model's name, or a parameter missing)."""

    def __init__(self, param: str | None, message: str) -> None:
        if len(message) > MAX_MESSAGE:
            message = message[: MAX_MESSAGE - 1] + "…"
        super().__init__(message)
        self.param = param


def build(name: object, params: dict[str, Any]) -> BRDF:
    """The model ``name`` with ``params``, checked as above; `MaterialError` otherwise."""
    if not isinstance(name, str):
        raise MaterialError(None, f"expected the name of a gonio.brdf model, got {name!r}")
    if name == "sum":
        return _build_sum(params)
    for key, value in params.items():
        if isinstance(value, bool):
            raise MaterialError(key, f"expected a number or a name, not yes/no (got {value})")
    try:
        model = create(name, **params)
    except GonioError as exc:
        message = str(exc)
        words = re.findall(r"[A-Za-z_]\w*", message)
        param = next((w for w in words if w in params), None)
        raise MaterialError(param, message) from None
    for key in REFLECTANCES:
        if key in model.params:
            value = np.asarray(model.params[key], dtype=np.float64)
            if np.any(value > 1.0):
                raise MaterialError(
                    key, f"a reflectance is at most 1 (energy conservation), got {_show(value)}"
                )
    if "kd" in model.params:
        kd = np.asarray(model.params["kd"], dtype=np.float64)
        other, what = _specular_albedo(model)
        if other is not None and np.any(kd + other > 1.0 + 1e-12):
            raise MaterialError(
                "kd",
                f"kd + {what} is {_show(kd + other)}; expected at most 1 (energy conservation)",
            )
    return model


def _build_sum(params: dict[str, Any]) -> BRDF:
    """A `Sum` whose components are each checked by `build`, then their albedos' bound."""
    components = params.get("components")
    if set(params) != {"components"} or not isinstance(components, list) or not components:
        raise MaterialError("components", "a sum takes one parameter, components: a list of models")
    built = []
    for j, item in enumerate(components):
        if not isinstance(item, dict):
            raise MaterialError("components", f"components.{j}: expected a model, got {item!r}")
        rest = {k: v for k, v in item.items() if k != "name"}
        try:
            built.append(build(item.get("name"), rest))
        except MaterialError as exc:
            where = f"components.{j}" + (f".{exc.param}" if exc.param else ".name")
            raise MaterialError(where, str(exc)) from None
    model = Sum(built)
    total = sum(np.atleast_1d(albedo_bound(c)) for c in built)
    if np.any(total > 1.0 + 1e-12):
        raise MaterialError(
            "components",
            f"the components' albedos add up to {_show(np.asarray(total))}; expected at most 1 "
            "(energy conservation)",
        )
    return model


def albedo_bound(model: BRDF) -> np.ndarray:
    """An upper bound of ``model``'s directional albedo at normal incidence, per channel
    (shape () or (3,)); 0 for a model with no known bound."""
    if "albedo" in model.params:
        return np.asarray(model.params["albedo"], dtype=np.float64)
    if isinstance(model, Sum):
        return np.asarray(sum(albedo_bound(c) for c in model.components), dtype=np.float64)
    spec, _ = _specular_albedo(model)
    kd = np.asarray(model.params.get("kd", 0.0), dtype=np.float64)
    return np.asarray(kd if spec is None else kd + spec, dtype=np.float64)


def _specular_albedo(model: BRDF) -> tuple[np.ndarray | None, str]:
    """An upper bound of the specular part's albedo at normal incidence, and its words."""
    if "ks" in model.params:
        return np.asarray(model.params["ks"], dtype=np.float64), "ks"
    fresnel = getattr(model, "fresnel", None)
    if callable(fresnel):
        f = np.asarray(fresnel(np.ones(1 if not getattr(fresnel, "is_rgb", False) else (1, 1))))
        return f.reshape(-1), "the Fresnel reflectance at normal incidence"
    return None, ""


def _show(value: np.ndarray) -> str:
    return ", ".join(f"{v:.4g}" for v in np.ravel(value))


def parameters(name: str) -> tuple[list[str], list[str]]:
    """(every parameter, the required ones) of the model registered as ``name``."""
    signature = inspect.signature(model_class(name).__init__).parameters
    accepted = [p for p in signature.values() if p.name not in ("self", "factory")]
    return [p.name for p in accepted], [p.name for p in accepted if p.default is p.empty]


_NAME = {
    "enum": names(),
    "description": "The model (docs/explanations/brdf.md); its parameters sit beside the name.",
}


def _params_schema(model: str, depth: int) -> dict[str, Any]:
    """The JSON Schema of ``model``'s parameters (a sum's components ``depth`` levels
    deep; deeper only their names): each by name, the required ones, no yes/no."""
    every, required = parameters(model)
    value: dict[str, Any] = {"not": {"type": "boolean"}}
    if model == "sum":
        value = {"type": "array", "minItems": 1, "items": _flat_schema(depth - 1)}
    return {
        "properties": dict.fromkeys(every, value),
        "required": required,
        "additionalProperties": False,
    }


def _is(model: str) -> dict[str, Any]:
    return {"required": ["name"], "properties": {"name": {"const": model}}}


def _flat_schema(depth: int) -> dict[str, Any]:
    """The JSON Schema of ``{name: MODEL, PARAM: value, …}``."""
    out: dict[str, Any] = {"type": "object", "required": ["name"], "properties": {"name": _NAME}}
    if depth >= 0:
        branches = []
        for model in names():
            then = _params_schema(model, depth)
            then["properties"] = {"name": True, **then["properties"]}
            branches.append({"if": _is(model), "then": then})
        out["allOf"] = branches
    return out


def material_schema(*, nested: bool) -> dict[str, Any]:
    """The JSON Schema of a material as a file writes it: ``name`` and the model's
    parameters beside it (as `build` takes them); ``nested``: or under ``params`` (as
    `MaterialSpec` reads it too). The values' own checks (reflectances, energy
    conservation) are `build`'s only."""
    flat = _flat_schema(depth=0)
    if not nested:
        return flat
    under = {
        "type": "object",
        "required": ["name", "params"],
        "properties": {"name": _NAME, "params": {"type": "object"}},
        "additionalProperties": False,
        "allOf": [
            {"if": _is(model), "then": {"properties": {"params": _params_schema(model, 0)}}}
            for model in names()
        ],
    }
    return {"if": {"required": ["params"]}, "then": under, "else": flat}


def _material_json_schema(schema: dict[str, Any]) -> None:
    description = schema.get("description")
    schema.clear()
    schema.update(material_schema(nested=True))
    if description is not None:
        schema["description"] = description


class MaterialSpec(Strict):
    """A `gonio.brdf` model: ``name`` and its parameters beside it (numbers, names, RGB
    lists), or under ``params``; a relative ``path`` (a tabulated material's file) is
    relative to the file that names it."""

    model_config = ConfigDict(json_schema_extra=_material_json_schema)

    name: str
    params: dict[str, Any] = Field(default_factory=dict)  # checked by gonio.brdf.material

    @model_validator(mode="before")
    @classmethod
    def _flat(cls, data: Any, info: ValidationInfo) -> Any:
        """Accept ``{name: ggx, alpha: 0.1}`` as well as ``{name: ggx, params: {...}}``; a
        relative ``path`` (a tabulated material's file) is relative to the scene file."""
        if isinstance(data, dict) and "params" not in data:
            rest = {k: v for k, v in data.items() if k != "name"}
            data = {"name": data.get("name"), "params": rest}
        folder = Path((info.context or {}).get("path", "")).parent
        given = data.get("params") if isinstance(data, dict) else None
        if isinstance(given, dict) and isinstance(given.get("path"), str):
            # Absolute once resolved, so the spec written back as text (a journaled scene)
            # names the same file from any folder.
            path = (folder / Path(given["path"]).expanduser()).resolve()
            data = {**data, "params": {**given, "path": str(path)}}
        return data

    @model_validator(mode="after")
    def _buildable(self) -> MaterialSpec:
        self.model()
        return self

    def model(self) -> BRDF:
        try:
            return build(self.name, self.params)
        except MaterialError as exc:
            raise field_error(exc.param or "name", str(exc)) from None
