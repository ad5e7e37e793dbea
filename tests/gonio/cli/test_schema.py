"""`gonio schema KIND`, the shipped JSON Schemas and the configuration reference: the
command prints the shipped file; every shipped config names its schema on its first line
and validates against it, read as the loader reads YAML (1.1) and as an editor does
(1.2); the generated files are what `tools.reference_config` writes now; and the schema
refuses what the loader refuses — every shipped config mutated (an unknown key, a key
removed, values of other types, out of bounds, not a choice, a list item repeated, at
every depth) — except the checks `tools.reference_config.LOADER_ONLY` lists, each shown
refused by the loader and accepted by the schema."""

from __future__ import annotations

import copy
import functools
import json
import re
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml
from pydantic import BaseModel, ValidationError

from gonio.cli.schema import KINDS, schema, shipped
from gonio.config import ConfigError, dotted, located, untagged
from gonio.planner.files import load_plan_source
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.tradeoff.grid import load_sweep
from tests.conftest import CONFIGS, CliResult
from tools.reference_config import (
    FOLDERS,
    LOADER_ONLY,
    LoaderCheck,
    editor_line,
    outputs,
    patched,
    stale,
)

SHIPPED = sorted(CONFIGS.glob("*/*.yaml"))
KIND_OF = {folder: kind for kind, folder in FOLDERS.items()}


def kind_of(path: Path) -> str:
    return KIND_OF[path.parent.name]


class Yaml12Loader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2's core schema, as an editor's YAML language
    server reads a file: only true/false are booleans, 2.0e5 is a number."""


Yaml12Loader.yaml_implicit_resolvers = {
    first: [
        (tag, regex) for tag, regex in resolvers if not tag.endswith((":bool", ":int", ":float"))
    ]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
for _tag, _regex, _first in (
    ("bool", r"^(?:true|True|TRUE|false|False|FALSE)$", "tTfF"),
    ("int", r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$", "-+0123456789"),
    (
        "float",
        r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
        r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$",
        "-+0123456789.",
    ),
):
    Yaml12Loader.add_implicit_resolver(
        f"tag:yaml.org,2002:{_tag}", re.compile(_regex), list(_first)
    )


@functools.cache
def validator(kind: str) -> jsonschema.protocols.Validator:
    return jsonschema.Draft202012Validator(schema(kind))


def schema_refuses(kind: str, data: Any) -> bool:
    return not validator(kind).is_valid(data)


def loader_refusal(kind: str, data: Any, path: Path) -> tuple[str, str] | None:
    """(field, message) of the loader's refusal of ``data`` read from ``path`` (its
    model's validation, as `gonio.config.load` does after parsing), None if accepted."""
    model: type[BaseModel] = KINDS[kind][0]
    try:
        model.model_validate(data, context={"path": path})
    except ValidationError as exc:
        loc, message = located(exc.errors(include_url=False)[0])
        return dotted(untagged(data, loc)), message
    return None


# -- the command and the shipped files ---------------------------------------------------


@pytest.mark.parametrize("kind", list(KINDS))
def test_gonio_schema_prints_the_shipped_schema(
    kind: str, run_gonio: Callable[..., CliResult]
) -> None:
    result = run_gonio("schema", kind)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["title"] == f"gonio {kind} file"
    assert result.stdout == shipped(kind).read_text(encoding="utf-8")


def test_an_unknown_kind_is_one_usage_line(run_gonio: Callable[..., CliResult]) -> None:
    result = run_gonio("schema", "plans")
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "invalid choice: 'plans'" in result.stderr


@pytest.mark.parametrize("kind", list(KINDS))
def test_the_schemas_are_draft_2020_12_and_every_field_is_described(kind: str) -> None:
    data = json.loads(shipped(kind).read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(data)
    assert data["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert "$id" not in data and data["title"] and data["description"]
    undescribed = []

    def walk(node: dict[str, Any], where: str) -> None:
        for name, field in node.get("properties", {}).items():
            if not field.get("description"):
                undescribed.append(f"{where}{name}")

    walk(data, "")
    for name, definition in data.get("$defs", {}).items():
        walk(definition, f"{name}.")
    assert undescribed == []


def test_the_generated_files_are_what_the_models_generate_now() -> None:
    assert list(stale()) == [], "regenerate with: python -m tools.reference_config"


def test_a_generated_file_nothing_generates_any_more_is_stale(tmp_path: Path) -> None:
    """A kind renamed or removed leaves no schema or page behind unnoticed."""
    for path, text in outputs().items():
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text(text, encoding="utf-8")
    assert list(stale(tmp_path)) == []
    left = [Path("gonio/schemas/old.schema.json"), Path("docs/reference/config/old.md")]
    for path in left:
        (tmp_path / path).write_text("{}", encoding="utf-8")
    assert sorted(stale(tmp_path)) == sorted(left)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shipped_config_names_its_schema_on_its_first_line(path: Path) -> None:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    assert first == editor_line(kind_of(path))
    named = (path.parent / first.partition("$schema=")[2]).resolve()
    assert named == shipped(kind_of(path)).resolve() and named.is_file()


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_shipped_config_validates_as_the_loader_and_an_editor_read_it(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    as_loader = yaml.safe_load(text)  # YAML 1.1, as gonio.config reads it
    as_editor = yaml.load(text, Loader=Yaml12Loader)
    assert as_loader == as_editor, "the file means other values in YAML 1.1 and 1.2"
    checker = jsonschema.Draft202012Validator.FORMAT_CHECKER
    errors = list(
        jsonschema.Draft202012Validator(schema(kind_of(path)), format_checker=checker).iter_errors(
            as_loader
        )
    )
    assert [f"{e.json_path}: {e.message}" for e in errors] == []
    assert loader_refusal(kind_of(path), as_loader, path) is None


# -- agreement on bad files --------------------------------------------------------------

#: More documents to mutate: shipped ones with the sections no shipped file has.
EXTRA_BASES: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = (
    ("plans/quickstart.yaml", (
        ("sampling", {"strategy": "adaptive", "target": 400, "seed": 1,
                      "adaptive": {"survey": 64, "model": "lambert+ggx", "floor": 0.3}}),
        ("acquisition.health", {"every_samples": 50, "poll_s": 5.0}),
    )),
    ("plans/quickstart.yaml", (
        ("sampling", {"strategy": "grid", "counts": {"theta_h": 4, "theta_d": 3, "phi_d": 2},
                      "warps": {"theta_h": {"power": 2}}}),
    )),
    ("scenes/matte.yaml", (
        ("material", {"name": "sum", "params": {"components": [
            {"name": "lambert", "albedo": 0.3}, {"name": "phong", "n": 20, "ks": 0.2}]}}),
        ("effects", {"stray_light": {"power_w": 1e-9}, "source_drift": None}),
        ("faults", [{"kind": "motor_fault", "at": [3, 5], "axis": "light_elevation",
                     "flags": ["overload", "overheating"]},
                    {"kind": "overheat", "rate": 0.1, "temperature_c": 90, "for_s": 30}]),
    )),
    ("sweeps/quick.yaml", (
        ("axes.effects", ["scene", ["shot_noise"], {"without": ["read_noise"]}]),
        ("exclude", [{"sampling": ["warped", "stratified"], "samples": 100}]),
    )),
)  # fmt: skip

#: Values a mutation puts in place of one of each type (the original's type decides).
REPLACEMENTS: dict[type, tuple[Any, ...]] = {
    bool: (1, "text", None),
    int: ("text", True, -1, 0, 0.5, 1e12, 3e19, None),
    float: ("text", -1, 0, 0.5, 1e12, 3e19, None),
    str: (123, "not-a-choice", "", None),
    list: ("text", [], {"a": 1}, None),
    dict: ("text", [1], {}, None),
    type(None): ("text", 1),
}


def _nodes(
    data: Any, at: tuple[int | str, ...] = ()
) -> Iterator[tuple[tuple[int | str, ...], Any]]:
    yield at, data
    if isinstance(data, dict):
        for key, value in data.items():
            yield from _nodes(value, (*at, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            yield from _nodes(value, (*at, i))


def _set(data: Any, at: tuple[int | str, ...], value: Any, delete: bool = False) -> Any:
    out = copy.deepcopy(data)
    node = out
    for key in at[:-1]:
        node = node[key]
    if delete:
        del node[at[-1]]
    else:
        node[at[-1]] = value
    return out


def mutations(
    data: dict[str, Any],
) -> Iterator[tuple[str, tuple[int | str, ...], Callable[[], Any]]]:
    """(what, where, maker of the mutated document) of every mutation of ``data``: the
    document is copied only when made (most mutations repeat one of an earlier base)."""
    for at, value in _nodes(data):
        if isinstance(value, dict):
            unknown = {**value, "bogus_key": 1}
            yield (
                "unknown key",
                at,
                functools.partial(_set, data, at, unknown)
                if at
                else (lambda unknown=unknown: unknown),
            )
        if not at:
            continue
        if isinstance(at[-1], str):
            yield "missing", at, functools.partial(_set, data, at, None, delete=True)
        if isinstance(value, list) and value:
            yield "an item repeated", at, functools.partial(_set, data, at, [*value, value[0]])
        for other in REPLACEMENTS[type(value)]:
            yield f"value {other!r}", at, functools.partial(_set, data, at, other)


def _bases() -> Iterator[tuple[str, Path, dict[str, Any]]]:
    for path in SHIPPED:
        yield kind_of(path), path, yaml.safe_load(path.read_text(encoding="utf-8"))
    for name, patches in EXTRA_BASES:
        path = CONFIGS / name
        yield (
            kind_of(path),
            path,
            patched(yaml.safe_load(path.read_text(encoding="utf-8")), patches),
        )


def _at(data: Any, at: tuple[int | str, ...]) -> Any:
    return functools.reduce(lambda node, key: node[key], at, data)


def _lax(original: Any, mutated: Any) -> bool:
    """A value the loader converts and the schema refuses (`tools.reference_config.STRICTER`):
    0 or 1 for a yes/no."""
    return isinstance(original, bool) and mutated in (0, 1) and not isinstance(mutated, bool)


def test_the_schema_refuses_what_the_loader_refuses() -> None:
    unexplained, false_refusals, seen = [], [], set()
    counts = {"both refuse": 0, "both accept": 0, "loader only, listed": 0, "lax": 0}
    depths: set[tuple[str, int]] = set()
    for kind, path, base in _bases():
        assert loader_refusal(kind, base, path) is None and not schema_refuses(kind, base), path
        for what, at, make in mutations(base):
            if (kind, at, what) in seen:
                continue
            seen.add((kind, at, what))
            mutated = make()
            refusal = loader_refusal(kind, mutated, path)
            refused = schema_refuses(kind, mutated)
            where = f"{kind} {path.name} {what} at {'.'.join(map(str, at)) or '(top)'}"
            if refusal is not None and refused:
                counts["both refuse"] += 1
                depths.add((what.split(" ")[0], len(at)))
            elif refusal is None and not refused:
                counts["both accept"] += 1
            elif refusal is not None:
                checks = [c for c in LOADER_ONLY if c.kind == kind and not c.files]
                if any(c.matches(*refusal) for c in checks):
                    counts["loader only, listed"] += 1
                else:
                    unexplained.append(f"{where}: {refusal[0]}: {refusal[1]}")
            else:
                if what.startswith("value") and _lax(_at(base, at), _at(mutated, at)):
                    counts["lax"] += 1
                else:
                    error = next(validator(kind).iter_errors(mutated))
                    false_refusals.append(f"{where}: {error.json_path}: {error.message[:120]}")
    assert unexplained == [], "refused by the loader only, and not in LOADER_ONLY"
    assert false_refusals == [], "refused by the schema only"
    assert counts["both refuse"] > 1000 and counts["loader only, listed"] > 0, counts
    for what in ("unknown", "missing", "value"):  # each kind of mistake, at several depths
        assert len({d for w, d in depths if w == what}) >= 4, (what, sorted(depths))


def _example_data(check: LoaderCheck) -> tuple[Path, Any]:
    name, patches = check.example
    path = CONFIGS / name
    return path, patched(yaml.safe_load(path.read_text(encoding="utf-8")), patches)


def _full_loader(kind: str, path: Path) -> None:
    """The whole loader of ``kind``: the files a file names, and the rig model."""
    if kind == "plan":
        load_plan_source(path)
    elif kind == "rig":
        Rig.from_yaml(path)
    elif kind == "scene":
        rig = Rig.from_yaml(CONFIGS / "rigs" / "arch.yaml")
        load_scene(path, rig).check_rig(rig)
    else:
        load_sweep(path)


@pytest.mark.parametrize(
    "check", LOADER_ONLY, ids=[f"{c.kind}:{c.field or 'files'}:{c.message}" for c in LOADER_ONLY]
)
def test_each_loader_only_check_is_the_loader_s_alone(check: LoaderCheck, tmp_path: Path) -> None:
    path, data = _example_data(check)
    assert not schema_refuses(check.kind, data), "the schema refuses it too: not loader-only"
    if not check.files:
        refusal = loader_refusal(check.kind, data, path)
        assert refusal is not None and check.matches(*refusal), refusal
        return
    assert loader_refusal(check.kind, data, path) is None, "its model alone refuses it"
    configs = tmp_path / "configs"
    shutil.copytree(CONFIGS, configs)
    target = configs / path.parent.name / path.name
    target.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), encoding="utf-8")
    with pytest.raises(ConfigError) as refused:
        _full_loader(check.kind, target)
    message = str(refused.value)
    assert re.search(check.message, message), message
    assert check.field in message, message
