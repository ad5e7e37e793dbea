"""Every number a configuration file may give has the bounds its physics or its memory
allows, written in the shipped JSON Schemas (and so in the generated reference): no
number field is open at either end."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

SCHEMAS = sorted((Path(__file__).parents[2] / "gonio" / "schemas").glob("*.schema.json"))
_CHILDREN = ("items", "additionalProperties")
_ALTERNATIVES = ("anyOf", "oneOf", "allOf", "prefixItems")


def numbers(node: Any, where: str) -> Iterator[tuple[str, dict[str, Any]]]:
    """(field path, schema) of every number or integer schema under ``node``."""
    if isinstance(node, list):
        for item in node:
            yield from numbers(item, where)
        return
    if not isinstance(node, dict):
        return
    if node.get("type") in ("number", "integer"):
        yield where, node
    for key, value in node.items():
        if key == "properties":
            for name, field in value.items():
                yield from numbers(field, f"{where}.{name}")
        elif key == "$defs":
            for name, definition in value.items():
                yield from numbers(definition, name)
        elif key in _CHILDREN:
            yield from numbers(value, f"{where}[]")
        elif key in _ALTERNATIVES:
            yield from numbers(value, where)


def bound(schema: dict[str, Any], keys: tuple[str, str]) -> float | None:
    found = [schema[k] for k in keys if k in schema]
    return found[0] if found else None


@pytest.mark.parametrize("path", SCHEMAS, ids=[p.name for p in SCHEMAS])
def test_every_number_field_is_bounded_at_both_ends(path: Path) -> None:
    schema = json.loads(path.read_text(encoding="utf-8"))
    found = list(numbers(schema, ""))
    assert len(found) > 10
    open_ended = []
    for where, node in found:
        if "enum" in node or "const" in node:
            continue
        low = bound(node, ("minimum", "exclusiveMinimum"))
        high = bound(node, ("maximum", "exclusiveMaximum"))
        if low is None or high is None or not (math.isfinite(low) and math.isfinite(high)):
            open_ended.append(where)
    assert not open_ended, f"{path.name}: number fields without bounds: {open_ended}"
