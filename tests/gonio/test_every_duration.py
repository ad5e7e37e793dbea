"""Every duration (a field named ``…_s``) of every model a configuration file reaches is
bounded by `MAX_SECONDS`, however the number is written: a float, an integer, or the
text YAML 1.1 makes of ``1e300`` (no dot), which pydantic would read as the number."""

from __future__ import annotations

import types
import typing
from collections.abc import Iterator
from typing import Any

import pytest
from pydantic import BaseModel, ValidationError

from gonio.cli.schema import KINDS
from gonio.config import MAX_SECONDS, Strict, _scalar_kinds


def models(annotation: Any, seen: set[type[BaseModel]]) -> Iterator[type[BaseModel]]:
    """Every model an annotation reaches (through unions, containers, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        if annotation not in seen:
            seen.add(annotation)
            yield annotation
            for field in annotation.model_fields.values():
                yield from models(field.annotation, seen)
        return
    if typing.get_origin(annotation) is not None or isinstance(annotation, types.UnionType):
        for arg in typing.get_args(annotation):
            yield from models(arg, seen)


def subclasses(cls: type[Strict]) -> Iterator[type[Strict]]:
    for sub in cls.__subclasses__():
        yield sub
        yield from subclasses(sub)


SEEN: set[type[BaseModel]] = set()
REACHED = [m for model, _ in KINDS.values() for m in models(model, SEEN)]
# In the order the classes were made where two share a name (a set's order follows their
# ids, which differ between pytest-xdist's workers, and so would their tests).
STRICT = sorted(dict.fromkeys(subclasses(Strict)), key=lambda m: f"{m.__module__}.{m.__qualname__}")
DURATIONS = [
    (model, name)
    for model in STRICT
    for name, field in model.model_fields.items()
    if name.endswith("_s") and _scalar_kinds(field.annotation) & {int, float}
]


def test_every_configuration_model_is_strict() -> None:
    assert len(REACHED) > 40
    assert [m for m in REACHED if not issubclass(m, Strict)] == []


def test_the_durations_are_found() -> None:
    names = {f"{model.__name__}.{name}" for model, name in DURATIONS}
    assert {"PyMeasureInterfaceSpec.timeout_s", "HealthSpec.poll_s"} <= names
    assert len(DURATIONS) > 20


@pytest.mark.parametrize("value", [1e300, "1e300", "1.5e11", 10**12, "-1e300"])
@pytest.mark.parametrize(
    ("model", "name"), DURATIONS, ids=[f"{m.__name__}.{n}" for m, n in DURATIONS]
)
def test_a_duration_beyond_the_bound_is_refused(
    model: type[BaseModel], name: str, value: object
) -> None:
    with pytest.raises(ValidationError) as caught:
        model.model_validate({name: value})
    first = caught.value.errors()[0]
    assert str(first["msg"]).endswith(f"{name}: expected at most {MAX_SECONDS:g} s (got {value!r})")
