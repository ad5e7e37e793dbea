"""YAML configuration files read into pydantic models, with one-line errors.

Files are parsed with PyYAML's safe loader (no object construction). Any mistake —
unreadable file, not YAML, wrong shape, a field out of range, an unknown field — raises
`ConfigError` whose message is one line per problem (the first few, `SHOWN_PROBLEMS`)
naming the file, the line when known, the field path and what was expected, e.g.::

    configs/plans/quick.yaml:7: sampling.counts.hbar: Input should be greater than 0 (got -3)

an unknown field with the closest known one (``did you mean 'sampling'?``).
"""

from __future__ import annotations

import difflib
import functools
import math
import types
import typing
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError, model_validator
from pydantic_core import ErrorDetails

from gonio.config.yaml_files import excerpt, key_label, line_of, read_bytes, read_yaml
from gonio.errors import ConfigError

__all__ = [
    "MAX_INTEGER",
    "MAX_SECONDS",
    "SHOWN_PROBLEMS",
    "ConfigError",
    "Strict",
    "describe",
    "dotted",
    "excerpt",
    "field_error",
    "line_of",
    "load",
    "located",
    "read_bytes",
    "read_yaml",
    "spec_text",
    "untagged",
]

M = TypeVar("M", bound=BaseModel)
#: How many of a file's problems an error names, one line each.
SHOWN_PROBLEMS = 5
#: How alike an unknown field's name must be to a known one to be suggested for it
#: (`difflib`'s ratio: a letter missed or swapped in a word of six or more).
SUGGEST_CUTOFF = 0.75


class Strict(BaseModel):
    """Base of every configuration model: unknown fields are mistakes, values are frozen.

    Its JSON Schema (`gonio.config_schema.json_schema`) describes the YAML a user writes:
    a validator that accepts another shape or checks a value says so to the schema
    (``json_schema_input_type`` of a ``mode="before"`` validator, ``json_schema_extra`` of
    a field), so that an editor
    refuses what the loader refuses wherever a schema can say it.
    """

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _plain_numbers(cls, data: Any) -> Any:
        """No yes/no where a number is expected (pydantic would read ``true`` as 1), no
        integer beyond 64 bits, no duration (``…_s``) beyond `MAX_SECONDS`."""
        if not isinstance(data, dict):
            return data
        for name, value in data.items():
            if not (isinstance(name, str) and name in cls.model_fields):
                continue
            kinds = _numeric_kinds(cls, name)
            if kinds is None:  # no number in this field: nothing to check
                continue
            for where, item in _leaves(name, value):
                if isinstance(item, bool):
                    if bool not in kinds:
                        raise field_error(where, f"expected a number, not yes/no (got {item})")
                    continue
                number = _as_number(item)
                if number is not None:
                    if int in kinds and float not in kinds and abs(number) > MAX_INTEGER:
                        raise field_error(
                            where, f"expected an integer below 2**63 (got {excerpt(item)})"
                        )
                    if name.endswith("_s") and MAX_SECONDS < abs(number) < math.inf:
                        raise field_error(
                            where, f"expected at most {MAX_SECONDS:g} s (got {excerpt(item)})"
                        )
        return data


#: The longest duration a configuration or an option may give (an exposure, a timeout), in
#: seconds: about 31 years, and within what Python's clocks can wait (`time.sleep` and
#: `select` take at most 2**63 ns, about 9.2e9 s, and raise `OverflowError` beyond).
MAX_SECONDS = 1e9
#: The largest magnitude of an integer a configuration may give (64 bits, signed).
MAX_INTEGER = 2**63 - 1


def _as_number(item: Any) -> int | float | None:
    """The number pydantic would read from a leaf: an int or a float as it is, a string
    of a number as parsed (YAML 1.1 reads ``1e300``, without a dot, as text, and pydantic
    then reads that text as the number), None for anything else."""
    if isinstance(item, int | float) and not isinstance(item, bool):
        return item
    if isinstance(item, str):
        text = item.strip().replace("_", "")
        try:
            return int(text)
        except ValueError:
            pass
        try:
            return float(text)
        except (ValueError, OverflowError):
            return None
    return None


def _leaves(path: str, value: Any, levels: int = 2) -> Iterator[tuple[str, Any]]:
    """(dotted path, value) of ``value`` and of the items of its lists and mappings,
    ``levels`` deep (a field's own nested models check themselves)."""
    if isinstance(value, list | tuple) and levels:
        for i, item in enumerate(value):
            yield from _leaves(f"{path}.{i}", item, levels - 1)
    elif isinstance(value, dict) and levels:
        for key, item in value.items():
            yield from _leaves(f"{path}.{key}", item, levels - 1)
    else:
        yield path, value


@functools.cache
def _numeric_kinds(model: type[BaseModel], name: str) -> frozenset[Any] | None:
    """The scalar types field ``name`` of ``model`` admits when a number is among them,
    else None: computed once per model and field (each load validates the same fields)."""
    kinds = _scalar_kinds(model.model_fields[name].annotation)
    return frozenset(kinds) if kinds & {int, float} else None


def _scalar_kinds(annotation: Any) -> set[Any]:
    """The scalar types an annotation admits (through unions, containers and
    `Annotated`, not into models)."""
    if annotation in (bool, int, float):
        return {annotation}
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return set()
    out: set[Any] = set()
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _scalar_kinds(typing.get_args(annotation)[0])
    if origin is not None or isinstance(annotation, types.UnionType):
        for arg in typing.get_args(annotation):
            if arg is not Ellipsis:
                out |= _scalar_kinds(arg)
    return out


#: Marks a validator's message that names the field it is about (see `field_error`).
_FIELD_MARK = "@field "


def field_error(path: str, message: str) -> ValueError:
    """An error for a model validator to raise about the field at the dotted ``path``
    (relative to the model it validates), so the one-line message names that field
    and its line in the file rather than the model's."""
    return ValueError(f"{_FIELD_MARK}{path}: {message}")


def located(error: ErrorDetails) -> tuple[tuple[int | str, ...], str]:
    """(field path, message) of one pydantic error, the path extended by `field_error`."""
    loc = tuple(error["loc"])
    message = str(error["msg"]).removeprefix("Value error, ")
    if message.startswith(_FIELD_MARK):
        path, _, message = message.removeprefix(_FIELD_MARK).partition(": ")
        loc += tuple(int(p) if p.isdigit() else p for p in path.split("."))
        return loc, message
    got = error.get("input")
    shown = "" if error["type"] == "missing" or isinstance(got, dict) else f" (got {excerpt(got)})"
    return loc, f"{message}{shown}"


def describe(error: ErrorDetails) -> str:
    """'field.path: message (got …)' for one pydantic error."""
    loc, message = located(error)
    return f"{dotted(loc)}: {message}"


def dotted(loc: Sequence[int | str]) -> str:
    """A field path as ``a.b.0.c``, each part as `key_label` shows it."""
    return ".".join(key_label(p) for p in loc) or "(top level)"


def untagged(data: Any, loc: Sequence[int | str]) -> tuple[int | str, ...]:
    """``loc`` without the tags pydantic inserts for a union told apart by ``kind``
    (``source.point.distance_mm`` → ``source.distance_mm``): a key absent from the
    mapping the data has there, equal to that mapping's ``kind`` (or to the data, for a
    bare kind such as ``interface: serial``)."""
    out: list[int | str] = []
    for key in loc:
        tag = data.get("kind") if isinstance(data, dict) else data
        if isinstance(key, str) and tag == key and not (isinstance(data, dict) and key in data):
            continue
        out.append(key)
        if isinstance(data, dict):
            data = data.get(key)
        elif isinstance(data, list) and isinstance(key, int) and 0 <= key < len(data):
            data = data[key]
        else:
            data = None
    return tuple(out)


def spec_text(spec: BaseModel) -> bytes:
    """A validated model as YAML text that reads back as the same model: the text of a
    configuration made in code (every field given, floats written exactly)."""
    data = spec.model_dump(mode="json")
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True).encode("utf-8")


def load(
    path: str | Path,
    model: type[M],
    context: dict[str, Any] | None = None,
    *,
    raw: bytes | None = None,
) -> M:
    """Read ``path`` (or its bytes ``raw``, already read, so that what is validated is
    exactly what was hashed) and validate it as ``model`` (its validators see
    ``context`` and the ``path``); `ConfigError` on any mistake."""
    path = Path(path)
    data, node = read_yaml(path, raw)
    if not isinstance(data, dict):
        kind = "empty" if data is None else type(data).__name__
        raise ConfigError(f"{path}: expected a mapping of fields at the top level, got {kind}")
    try:
        return model.model_validate(data, context={**(context or {}), "path": path})
    except ValidationError as exc:
        raise ConfigError(problems(path, data, node, model, exc)) from None


def problems(
    path: Path, data: Any, node: yaml.Node | None, model: type[BaseModel], exc: ValidationError
) -> str:
    """The first `SHOWN_PROBLEMS` of a validation's problems, one line each in the order
    of their lines in the file (``FILE:LINE: field: message``), then how many more: an
    unknown field with the closest known one (`known_keys`), a missing one named where its
    mapping starts."""
    found = []
    for error in exc.errors(include_url=False):
        loc, message = located(error)
        loc = untagged(data, loc)
        if error["type"] == "extra_forbidden":
            line = key_line(node, loc)
            close = difflib.get_close_matches(
                str(loc[-1]), known_keys(model, loc[:-1]), n=1, cutoff=SUGGEST_CUTOFF
            )
            message = "unknown field" + (f"; did you mean {close[0]!r}?" if close else "")
        else:
            line = line_of(node, loc)
        where = f"{path}:{line}" if line is not None else str(path)
        found.append((line or 0, f"{where}: {dotted(loc)}: {message}"))
    shown = [text for _, text in sorted(found[:SHOWN_PROBLEMS], key=lambda f: f[0])]
    more = len(found) - len(shown)
    if more:
        shown.append(f"{path}: and {more} more problem{'s' if more > 1 else ''}")
    return "\n".join(shown)


def key_line(node: yaml.Node | None, loc: Sequence[int | str]) -> int | None:
    """The 1-based line of the key at ``loc`` (an unknown field's own line, not its
    value's), else as `line_of`."""
    parent = line_of(node, loc[:-1])
    for key in loc[:-1]:
        if isinstance(node, yaml.MappingNode):
            node = next((v for k, v in node.value if k.value == str(key)), None)
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and key < len(node.value):
            node = node.value[key]
        else:
            return parent
    if isinstance(node, yaml.MappingNode):
        for k, _ in node.value:
            if k.value == str(loc[-1]):
                return int(k.start_mark.line) + 1
    return parent


def known_keys(model: type[BaseModel], loc: Sequence[int | str]) -> list[str]:
    """The field names a model accepts at the mapping ``loc`` (through nested models,
    lists, mappings and unions: every alternative's fields)."""
    at: list[Any] = [model]
    for key in loc:  # a model's field, or a list's or mapping's entry
        inner: list[Any] = []
        for t in at:
            if isinstance(t, type) and issubclass(t, BaseModel):
                field = t.model_fields.get(str(key))
                if field is not None:
                    inner.extend(_held(field.annotation))
            elif isinstance(t, _Entries):
                inner.extend(_held(t.of))
        at = inner
    return sorted({
        name for t in at if isinstance(t, type) and issubclass(t, BaseModel)
        for name in t.model_fields
    })  # fmt: skip


class _Entries:
    """A list's or a mapping's entries, each an ``of``."""

    def __init__(self, of: Any) -> None:
        self.of = of


def _held(annotation: Any) -> list[Any]:
    """What a field of this annotation holds: its models (a union's alternatives,
    ``Annotated``'s type), or the entries of a list or mapping."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        return _held(args[0])
    if origin in (typing.Union, types.UnionType):
        return [m for arg in args for m in _held(arg)]
    if origin in (list, tuple, set, frozenset, Sequence):
        return [_Entries(arg) for arg in args if arg is not Ellipsis]
    if origin is dict:
        return [_Entries(args[1])]
    return [annotation]
