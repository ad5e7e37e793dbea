"""A rig file's section made from a driver's configuration: `driver_model` turns the
fields of a driver's dataclass (`drivers.serial_detector.SerialDetectorConfig`,
`drivers.pymeasure.PyMeasureDetectorConfig`), each with its type, default, description
and bounds (`drivers.described`), into a `Strict` pydantic model, so each is declared
once, in the driver; the section changes only what a file writes differently (a line
ending by name, a nested section's own model, a preset's field left out).

A model class built on one is declared ``class Spec(Fields)`` with ``Fields`` the
`driver_model` at run time and, for the type checker, a `Strict` class declaring the
few fields the program reads off the spec itself, typed as the model makes them (the
rest is read through the driver's configuration, ``spec.config()``).
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Iterable, Mapping
from typing import Annotated, Any, Literal

from pydantic import Field, create_model
from pydantic_core import PydanticUndefined

from gonio.config import Strict


def driver_model(
    name: str,
    config: type[Any],
    *,
    kind: tuple[str, str] | None = None,
    types: Mapping[str, Any] | None = None,
    defaults: Mapping[str, Any] | None = None,
    optional: Iterable[str] = (),
    required: Iterable[str] = (),
) -> type[Strict]:
    """A `Strict` model of the fields of the dataclass ``config``, in its order, each
    with its default, ``doc`` as the description and its bounds; first a ``kind`` field
    (``(tag, description)``: ``Literal[tag]``, required) when given. ``types``: a
    field's type as a file writes it, when it differs; ``defaults``: a default as a file
    writes it; ``optional``: fields that may be left out (None: a preset gives them);
    ``required``: fields a file must give though the dataclass has a default."""
    types, defaults = dict(types or {}), dict(defaults or {})
    optional, required = frozenset(optional), frozenset(required)
    hints = typing.get_type_hints(config)
    fields: dict[str, Any] = {}
    if kind is not None:
        tag, description = kind
        fields["kind"] = (Literal[tag], Field(description=description))
    for f in dataclasses.fields(config):
        meta = f.metadata
        annotation = types.get(f.name, hints[f.name])
        if meta.get("items"):
            annotation = _items_bounded(annotation, meta["items"])
        if f.name in optional:
            annotation, default = annotation | None, None
        elif f.name in required:
            default = PydanticUndefined
        elif f.name in defaults:
            default = defaults[f.name]
        elif f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = PydanticUndefined
        field = Field(default, description=meta["doc"], **meta["bounds"])
        fields[f.name] = (annotation, field)
    return create_model(name, __base__=Strict, __module__=__name__, **fields)


def _items_bounded(annotation: Any, bounds: dict[str, Any]) -> Any:
    """``tuple[float, ...]`` or ``tuple[float, float]`` with each item bounded."""
    args = typing.get_args(annotation)
    annotated: Any = Annotated
    generic: Any = tuple
    item = annotated[args[0], Field(**bounds)]
    if len(args) == 2 and args[1] is Ellipsis:
        return generic[item, ...]
    return generic[tuple(item for _ in args)]
