"""A plan's expected material: a `gonio.brdf` model named with its parameters beside it
(``material: {name: ..., ...}``), as a model, and the JSON Schema of such a field."""

from __future__ import annotations

from typing import Any

from gonio import brdf
from gonio.brdf import MaterialError, build, material_schema
from gonio.config import field_error


def material_model(material: dict[str, Any]) -> brdf.BRDF:
    """An expected material (its name, a `gonio.brdf` model, and its parameters beside
    it) as a model; a field error naming what is wrong."""
    if "name" not in material:
        raise field_error("material", "expected a name (a gonio.brdf model) and its parameters")
    params = dict(material)
    name = params.pop("name")
    try:
        return build(name, params)
    except MaterialError as exc:
        raise field_error(f"material.{exc.param or 'name'}", str(exc)) from None


def flat_material(schema: dict[str, Any]) -> None:
    """A material field's JSON Schema (`gonio.brdf.material_schema`, flat), written when
    a schema is asked for: it reads every model's parameters, which loads their modules."""
    schema.update(material_schema(nested=False))
