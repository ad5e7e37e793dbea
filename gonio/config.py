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
import math
import types
import typing
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError, model_validator
from pydantic_core import ErrorDetails

from gonio.errors import GonioError

M = TypeVar("M", bound=BaseModel)
#: How many of a file's problems an error names, one line each.
SHOWN_PROBLEMS = 5
#: How alike an unknown field's name must be to a known one to be suggested for it
#: (`difflib`'s ratio: a letter missed or swapped in a word of six or more).
SUGGEST_CUTOFF = 0.75


class ConfigError(GonioError):
    """A configuration file that cannot be used; the message is one line per problem."""


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
            field = cls.model_fields.get(name) if isinstance(name, str) else None
            if field is None:
                continue
            kinds = _scalar_kinds(field.annotation)
            for where, item in _leaves(name, value):
                if isinstance(item, bool):
                    if bool not in kinds and kinds & {int, float}:
                        raise field_error(where, f"expected a number, not yes/no (got {item})")
                    continue
                number = _as_number(item) if kinds & {int, float} else None
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


def read_bytes(path: Path) -> bytes:
    """The file's bytes, as UTF-8 text checked; ConfigError if it cannot be read."""
    try:
        raw = path.read_bytes()
        raw.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ConfigError(f"{shown_path(path)}: cannot read the file: {reason}") from None
    return raw


#: The longest path a message shows whole; a longer one keeps its start and its end.
PATH_SHOWN = 160


def shown_path(path: Path | str) -> str:
    """``path`` as a message shows it: whole, or cut in the middle when it is longer
    than `PATH_SHOWN` characters (a file name nobody could have meant)."""
    text = str(path)
    if len(text) <= PATH_SHOWN:
        return text
    half = PATH_SHOWN // 2
    return f"{text[:half]}…{text[-half:]}"


#: The largest configuration file read, in bytes (the shipped ones are under 5 KB).
MAX_BYTES = 1 << 20
#: The deepest nesting of mappings and lists, aliases expanded.
MAX_DEPTH = 64
#: The most aliases (``*name``) in one document.
MAX_ALIASES = 1000
#: The most values in one document with every alias expanded (a "billion laughs"
#: document expands a few hundred bytes to billions of values).
MAX_NODES = 100_000
#: The longest excerpt of a value a message shows.
EXCERPT = 40

#: PyYAML's safe loader, its C version (libyaml, about ten times faster) when installed.
Loader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def excerpt(value: Any) -> str:
    """``repr(value)`` cut to a short excerpt (a message never echoes a whole value)."""
    text = repr(value)
    return text if len(text) <= EXCERPT else f"{text[: EXCERPT - 1]}…"


def key_label(key: int | str) -> str:
    """A mapping key or list index as a message shows it: as written (cut to an excerpt)
    when it is printable without blanks at its ends, else as an excerpt of its repr (a
    key of blanks or line breaks keeps the message on one line)."""
    text = str(key)
    if not (text.isprintable() and text == text.strip() and text):
        return excerpt(key)
    return text if len(text) <= EXCERPT else f"{text[: EXCERPT - 1]}…"


def read_yaml(path: Path, raw: bytes | None = None) -> tuple[Any, yaml.Node | None]:
    """(data, node tree) of a YAML file (or of its bytes ``raw``, already read);
    ConfigError if it cannot be read or parsed, or exceeds the bounds above (size,
    nesting, aliases and their expansion), or gives a key twice in a mapping."""
    raw = read_bytes(path) if raw is None else raw
    if len(raw) > MAX_BYTES:
        raise ConfigError(
            f"{path}: the file has {len(raw)} bytes; expected at most {MAX_BYTES} "
            "for a configuration file"
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: cannot read the file: {exc}") from None
    try:
        return _parse(path, text, Loader)
    except yaml.YAMLError as exc:
        error = exc
    if Loader is not yaml.SafeLoader:  # the pure-Python loader's words for the mistake
        try:
            _parse(path, text, yaml.SafeLoader)
        except yaml.YAMLError as exc:
            error = exc
    mark = getattr(error, "problem_mark", None)
    where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    raise ConfigError(f"{where}: not valid YAML: {problem}") from None


def _parse(
    path: Path, text: str, loader_class: type[yaml.SafeLoader]
) -> tuple[Any, yaml.Node | None]:
    """`read_yaml` with one loader; `yaml.YAMLError` if the text is not YAML."""
    _check_events(path, text, loader_class)
    loader = loader_class(text)
    try:
        node = loader.get_single_node()
        if node is not None:
            _refuse_duplicate_keys(path, node)
        return (None if node is None else loader.construct_document(node)), node
    finally:
        loader.dispose()


def _check_events(path: Path, text: str, loader_class: type[yaml.SafeLoader]) -> None:
    """`ConfigError` unless the document's nesting, aliases and size with every alias
    expanded are within bounds: one pass over the parser's events (linear time and no
    recursion, however deep or aliased the document)."""
    # Per open collection: [values under it, deepest nesting under it, anchor or None].
    stack: list[list[Any]] = [[0, 0, None]]
    anchors: dict[str, tuple[int, int]] = {}  # anchor -> (values, nesting) it expands to
    aliases = 0

    def refuse(event: yaml.Event, what: str) -> ConfigError:
        mark = event.start_mark
        return ConfigError(f"{path}:{mark.line + 1}: {what}" if mark else f"{path}: {what}")

    def add(values: int, depth: int, event: yaml.Event) -> None:
        top = stack[-1]
        top[0] += values
        top[1] = max(top[1], depth + 1)
        if len(stack) - 1 + depth > MAX_DEPTH:
            raise refuse(
                event, f"nested more than {MAX_DEPTH} levels deep; expected a flatter document"
            )
        if stack[0][0] + sum(s[0] for s in stack[1:]) > MAX_NODES:
            raise refuse(
                event,
                f"more than {MAX_NODES} values (aliases expanded); expected a smaller document",
            )

    for event in yaml.parse(text, Loader=loader_class):
        if isinstance(event, yaml.AliasEvent):
            aliases += 1
            if aliases > MAX_ALIASES:
                raise refuse(event, f"more than {MAX_ALIASES} aliases; expected fewer")
            if event.anchor not in anchors:
                if any(s[2] == event.anchor for s in stack):
                    raise refuse(
                        event, f"*{str(event.anchor)[:EXCERPT]}: an alias inside the value it names"
                    )
                continue  # undefined: the composer says so
            values, depth = anchors[event.anchor]
            add(values, depth, event)
        elif isinstance(event, yaml.ScalarEvent):
            add(1, 0, event)
            if event.anchor is not None:
                anchors[event.anchor] = (1, 0)
        elif isinstance(event, yaml.CollectionStartEvent):
            stack.append([1, 1, event.anchor])
            add(0, 0, event)
        elif isinstance(event, yaml.CollectionEndEvent):
            values, depth, anchor = stack.pop()
            if anchor is not None:
                anchors[anchor] = (values, depth)
            add(values, depth, event)


def _refuse_duplicate_keys(path: Path, node: yaml.Node) -> None:
    """`ConfigError` at the second occurrence of a key in any mapping (PyYAML would keep
    the last value silently); each node visited once, however often it is aliased."""
    stack = [node]
    visited: set[int] = set()
    while stack:
        n = stack.pop()
        if id(n) in visited:
            continue
        visited.add(id(n))
        if isinstance(n, yaml.MappingNode):
            seen: set[str] = set()
            for key, value in n.value:
                if isinstance(key, yaml.ScalarNode):
                    if key.value in seen:
                        raise ConfigError(
                            f"{path}:{key.start_mark.line + 1}: {key_label(key.value)}: this key "
                            "is given twice in the same mapping; expected each key once"
                        )
                    seen.add(key.value)
                stack.append(value)
        elif isinstance(n, yaml.SequenceNode):
            stack.extend(n.value)


def line_of(node: yaml.Node | None, loc: Sequence[int | str]) -> int | None:
    """The 1-based line of the value at ``loc`` in a composed YAML tree (or of the
    deepest existing parent), None without a tree."""
    line = None if node is None else node.start_mark.line + 1
    for key in loc:
        if isinstance(node, yaml.MappingNode):
            match = next((v for k, v in node.value if k.value == str(key)), None)
            if match is None:  # a missing field: point at its parent mapping
                break
            node = match
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and key < len(node.value):
            node = node.value[key]
        else:
            break
        line = node.start_mark.line + 1
    return line


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
