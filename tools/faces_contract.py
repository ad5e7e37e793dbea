"""An import-linter contract type: every package is imported through its face.

A *room* is each subpackage of the ``containers`` (``gonio.rig``, ``drivers.dynamixel``,
``sim.peers``, ...). From outside a room, a module may import the room itself (its face,
the ``__init__``) and a module ``room.x`` only where ``x`` is a name of the face (its
``__all__``: a module the face offers as a namespace, a file format or a figure kind,
or a function of the same name as its module); any deeper module only where
``public_modules`` names it. Imports inside a room are the room's own business.

The face's names are read from the room's ``__init__.py`` without importing it:
``__all__``'s strings, and the keys of ``WHERE`` where ``__all__`` is ``list(WHERE)`` or
holds ``*WHERE`` (the lazy faces of `gonio.faces`).

Registered in pyproject.toml (``contract_types = ["faces: tools.faces_contract.FacesContract"]``)
and run by ``lint-imports``; tools/ is beside the package, which never imports it.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path
from typing import cast

import grimp
from importlinter import Contract, ContractCheck, fields, output


def face_names(init: Path) -> set[str]:
    """The names a package's ``__init__.py`` exports (its ``__all__``, ``WHERE`` included)."""
    tree = ast.parse(init.read_text(encoding="utf-8"))
    names: set[str] = set()
    where: set[str] = set()
    uses_where = False
    for node in tree.body:
        if not isinstance(node, (ast.Assign, ast.AnnAssign)) or node.value is None:
            continue
        target = node.targets[0] if isinstance(node, ast.Assign) else node.target
        if not isinstance(target, ast.Name):
            continue
        if target.id == "WHERE" and isinstance(node.value, ast.Dict):
            where = {
                k.value
                for k in node.value.keys
                if isinstance(k, ast.Constant) and isinstance(k.value, str)
            }
        elif target.id == "__all__":
            value = node.value
            if isinstance(value, ast.Call):  # list(WHERE)
                uses_where = True
            elif isinstance(value, (ast.List, ast.Tuple)):
                for e in value.elts:
                    if isinstance(e, ast.Constant) and isinstance(e.value, str):
                        names.add(e.value)
                    elif isinstance(e, ast.Starred):
                        uses_where = True
    return names | where if uses_where else names


def package_dir(package: str) -> Path:
    """The folder of a package, found without importing it (its top-level package's spec)."""
    top, *rest = package.split(".")
    spec = importlib.util.find_spec(top)
    if spec is None or spec.origin is None:
        raise ValueError(f"package {top!r} not found")
    return Path(spec.origin).parent.joinpath(*rest)


class FacesContract(Contract):
    """From outside a room, import the room's face (see the module's docstring).

    Options: ``containers`` (the packages whose subpackages are rooms) and
    ``public_modules`` (inner modules imported by name, each for a reason the
    configuration states: a driver's module that opens a port, kept out of its face).
    """

    type_name = "faces"

    containers = fields.ListField(subfield=fields.StringField())
    public_modules = fields.ListField(subfield=fields.StringField(), required=False, default=[])

    def rooms(self, graph: grimp.ImportGraph) -> list[str]:
        """Every subpackage of the containers that is a package."""
        found = []
        for container in cast("list[str]", self.containers):
            for child in sorted(graph.find_children(container)):
                if (package_dir(child) / "__init__.py").is_file():
                    found.append(child)
        return found

    def check(self, graph: grimp.ImportGraph, verbose: bool) -> ContractCheck:
        public = set(cast("list[str]", self.public_modules))
        illegal: list[dict[str, object]] = []
        for room in self.rooms(graph):
            faced = face_names(package_dir(room) / "__init__.py")
            for module in sorted(graph.find_descendants(room)):
                rest = module[len(room) + 1 :]
                if module in public or ("." not in rest and rest in faced):
                    continue
                for importer in sorted(graph.find_modules_that_directly_import(module)):
                    if importer == room or importer.startswith(room + "."):
                        continue
                    details = graph.get_import_details(importer=importer, imported=module)
                    lines = sorted({d["line_number"] for d in details})
                    illegal.append(
                        {"importer": importer, "imported": module, "room": room, "lines": lines}
                    )
        return ContractCheck(kept=not illegal, metadata={"illegal": illegal})

    def render_broken_contract(self, check: ContractCheck) -> None:
        output.print_error("Import these through the room's face (its __init__):", bold=False)
        output.new_line()
        for link in check.metadata["illegal"]:
            lines = ", ".join(map(str, link["lines"]))
            output.print_error(
                f"- {link['importer']} -> {link['imported']} (l.{lines}): "
                f"from {link['room']} import ...",
                bold=False,
            )
            output.new_line()
