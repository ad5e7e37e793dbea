"""Configuration files read safely: their bytes as UTF-8, then YAML parsed by PyYAML's
safe loader within bounds on size, nesting, aliases and expanded values (a hostile
document is one line, never a hang), duplicate keys refused; how messages show paths,
keys and values; and the line of a node in the file."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from gonio.errors import ConfigError


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

#: libyaml's words when a document nests deeper than its own bound (1000 levels).
LIBYAML_TOO_DEEP = "exceeded maximum nesting depth"

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
    if getattr(error, "problem", None) == LIBYAML_TOO_DEEP:
        # libyaml stops at its own bound, far deeper than ours: the pure-Python loader
        # would find the same refusal only after a scan quadratic in the depth (0.2 s
        # of CPU for 1000 brackets on one line)
        raise _too_deep(path, getattr(error, "problem_mark", None)) from None
    if Loader is not yaml.SafeLoader:  # the pure-Python loader's words for the mistake
        try:
            _parse(path, text, yaml.SafeLoader)
        except yaml.YAMLError as exc:
            error = exc
    mark = getattr(error, "problem_mark", None)
    where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    raise ConfigError(f"{where}: not valid YAML: {problem}") from None


def _too_deep(path: Path, mark: Any) -> ConfigError:
    """The refusal of a document nested deeper than `MAX_DEPTH`, at the line of ``mark``
    (a `yaml.Mark` of either loader, or None)."""
    where = f"{path}:{mark.line + 1}" if mark is not None else str(path)
    return ConfigError(
        f"{where}: nested more than {MAX_DEPTH} levels deep; expected a flatter document"
    )


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
            raise _too_deep(path, event.start_mark)
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
