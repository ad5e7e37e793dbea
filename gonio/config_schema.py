"""The JSON Schemas of the configuration files: what `gonio.config.load` reads, written
for an editor (draft 2020-12), from the same pydantic models.

`json_schema(model, title, description)` is one file kind's schema; `InSchema` adds to a
field's schema a check its validator makes, so the editor refuses what the loader does.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from pydantic import BaseModel, GetJsonSchemaHandler
from pydantic.json_schema import GenerateJsonSchema, JsonSchemaMode, JsonSchemaValue
from pydantic_core import CoreSchema

from gonio.config import MAX_INTEGER, MAX_SECONDS

#: The JSON Schema dialect of `json_schema`.
DRAFT = "https://json-schema.org/draft/2020-12/schema"
#: The order of a schema's keys in `json_schema`'s output (the rest follow as generated).
_FIRST_KEYS = ("$schema", "title", "description", "type", "properties", "required")


class ConfigSchema(GenerateJsonSchema):
    """Pydantic's JSON Schema generator (draft 2020-12) for configuration files: no title
    on fields or nested models (their descriptions say what they are), defaults made by
    factories written out like the others, and the bounds
    `Strict` adds to every model written out: integers of 64 bits, and durations (a
    field named ``…_s``, its lists' and mappings' numbers too) of at most `MAX_SECONDS`."""

    def field_title_should_be_set(self, schema: Any) -> bool:
        return False

    def get_default_value(self, schema: Any) -> Any:
        """A default made by a factory too (an empty list, a model's defaults)."""
        factory = schema.get("default_factory")
        if factory is not None and not schema.get("default_factory_takes_data"):
            return factory()
        return super().get_default_value(schema)

    def generate(self, schema: CoreSchema, mode: JsonSchemaMode = "validation") -> JsonSchemaValue:
        out = super().generate(schema, mode)
        for definition in out.get("$defs", {}).values():
            definition.pop("title", None)
        for node in _schemas(out):
            if isinstance(node.get("description"), str):
                node["description"] = one_paragraph(node["description"])
            if node.get("type") == "integer":
                _bound(node, MAX_INTEGER)
            for name, field in node.get("properties", {}).items():
                if name.endswith("_s"):
                    for leaf in _schemas(field, refs=False):
                        if leaf.get("type") in ("number", "integer"):
                            _bound(leaf, MAX_SECONDS)
        return out


#: Keywords whose value is a schema or a list of schemas.
_SUBSCHEMAS = (
    *("items", "prefixItems", "additionalProperties", "anyOf", "oneOf", "allOf", "not"),
    *("if", "then", "else", "contains", "propertyNames"),
)


def _schemas(node: Any, *, refs: bool = True) -> Iterator[dict[str, Any]]:
    """Every schema object in ``node`` (itself included), depth first; with ``refs``
    False, not the `$defs` (a field's own schema, without the models it refers to)."""
    if isinstance(node, list):
        for item in node:
            yield from _schemas(item, refs=refs)
    elif isinstance(node, dict):
        yield node
        for key, value in node.items():
            if key in ("properties", "$defs", "patternProperties"):
                if refs or key != "$defs":
                    for item in value.values():
                        yield from _schemas(item, refs=refs)
            elif key in _SUBSCHEMAS:
                yield from _schemas(value, refs=refs)


def one_paragraph(text: str) -> str:
    """A docstring's text on one line (its line breaks and indents made single spaces)."""
    return " ".join(text.split())


def _bound(node: dict[str, Any], limit: float) -> None:
    """Bound a number's schema to [−limit, limit] where it has no tighter bound."""
    upper = [node[k] for k in ("maximum", "exclusiveMaximum") if k in node]
    lower = [node[k] for k in ("minimum", "exclusiveMinimum") if k in node]
    if not upper or min(upper) > limit:
        node.pop("exclusiveMaximum", None)
        node["maximum"] = limit
    if not lower or max(lower) < -limit:
        node.pop("exclusiveMinimum", None)
        node["minimum"] = -limit


class InSchema:
    """``Annotated[T, InSchema(minimum=1)]``: ``T`` whose JSON Schema also says these
    keywords, for a check a validator makes (validation is unchanged: the validator's
    message stays the one a user reads)."""

    def __init__(self, **keywords: Any) -> None:
        self.keywords = keywords

    def __get_pydantic_json_schema__(
        self, schema: CoreSchema, handler: GetJsonSchemaHandler
    ) -> JsonSchemaValue:
        return {**handler(schema), **self.keywords}


def json_schema(model: type[BaseModel], title: str, description: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of the YAML files ``model`` loads, as `load`
    reads them: `ConfigSchema`'s, with ``title`` and ``description`` at the top."""
    out = model.model_json_schema(schema_generator=ConfigSchema)
    out.update({"$schema": DRAFT, "title": title, "description": one_paragraph(description)})
    first = {k: out.pop(k) for k in _FIRST_KEYS if k in out}
    return {**first, **out}
