"""`gonio schema KIND`: the JSON Schema (draft 2020-12) of a plan, rig, scene or sweep
file, generated from the models that load it, so that an editor completes and checks
the fields. The same schemas ship in the package (gonio/schemas/KIND.schema.json); a
YAML file names its own on its first line, for the YAML language server:
``# yaml-language-server: $schema=../../gonio/schemas/plan.schema.json``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from gonio.config_schema import json_schema
from gonio.planner import PlanSpec
from gonio.rig import RigSpec
from gonio.scene import Scene
from gonio.tradeoff import SweepSpec

#: Each kind of file: (the model that loads it, the schema's title).
KINDS: dict[str, tuple[type[BaseModel], str]] = {
    "plan": (PlanSpec, "gonio plan file"),
    "rig": (RigSpec, "gonio rig file"),
    "scene": (Scene, "gonio scene file"),
    "sweep": (SweepSpec, "gonio sweep file"),
}
#: The folder of the shipped schemas, ``KIND.schema.json`` each.
SCHEMAS = Path(__file__).resolve().parents[1] / "schemas"


def schema(kind: str) -> dict[str, Any]:
    """The JSON Schema of ``kind``'s files (one of `KINDS`)."""
    model, title = KINDS[kind]
    return json_schema(model, title, model.__doc__ or title)


def schema_text(kind: str) -> str:
    """`schema` as the text `gonio schema` prints and the shipped file holds."""
    return json.dumps(schema(kind), indent=2, ensure_ascii=False) + "\n"


def shipped(kind: str) -> Path:
    """The shipped schema file of ``kind``."""
    return SCHEMAS / f"{kind}.schema.json"


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser], help_: str) -> None:
    command = sub.add_parser(
        "schema",
        help=help_,
        description="Print the JSON Schema (draft 2020-12) of a kind of configuration file, "
        "generated from the models that load it. The same schemas ship as "
        "gonio/schemas/KIND.schema.json; a YAML file's first line "
        "'# yaml-language-server: $schema=PATH' makes an editor complete and check it.",
    )
    command.add_argument("kind", choices=list(KINDS), help="the kind of file")
    command.set_defaults(func=_cmd_schema)


def _cmd_schema(args: argparse.Namespace) -> int:
    print(schema_text(args.kind), end="")
    return 0
