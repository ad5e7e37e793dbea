"""The faces contract (tools/faces_contract.py) on a real package written to disk, its
import graph built by grimp as lint-imports builds it; and the layers contract names
every top-level module of gonio."""

from __future__ import annotations

import importlib
import pkgutil
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

import grimp
import pytest

import drivers
import gonio
import sim
from tools.faces_contract import FacesContract, face_names

ROOT = Path(__file__).resolve().parents[2]

FILES = {
    "__init__.py": "",
    "room/__init__.py": (
        "from typing import TYPE_CHECKING\n"
        "from houseq.room.inner import Thing\n"
        "WHERE = {'later': 'lazy', 'fmt': 'fmt'}\n"
        "__all__ = ['Thing', *WHERE]\n"
    ),
    "room/inner.py": "class Thing: ...\n",
    "room/lazy.py": "def later() -> None: ...\n",
    "room/fmt.py": "SIZE = 1\n",
    "room/port.py": "OPENS = True\n",
    "room/deep/__init__.py": "",
    "room/deep/leaf.py": "X = 1\n",
    "other.py": (
        "from houseq.room import Thing, later\n"
        "from houseq.room import fmt\n"
        "from houseq.room.port import OPENS\n"
    ),
}


@pytest.fixture
def package(tmp_path: Path) -> Iterator[Path]:
    for name, text in FILES.items():
        path = tmp_path / "houseq" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    sys.path.insert(0, str(tmp_path))
    yield tmp_path / "houseq"
    sys.path.remove(str(tmp_path))
    for name in [m for m in sys.modules if m == "houseq" or m.startswith("houseq.")]:
        del sys.modules[name]


def check(public: list[str]) -> list[tuple[str, str]]:
    contract = FacesContract("faces", {}, {"containers": ["houseq"], "public_modules": public})
    result = contract.check(grimp.build_graph("houseq"), verbose=False)
    assert result.kept == (not result.metadata["illegal"])
    return [(x["importer"], x["imported"]) for x in result.metadata["illegal"]]


def test_the_face_its_namespaces_and_the_public_modules_are_kept(package: Path) -> None:
    assert face_names(package / "room" / "__init__.py") == {"Thing", "later", "fmt"}
    assert check(["houseq.room.port"]) == []


def test_an_inner_module_imported_from_outside_breaks_the_contract(package: Path) -> None:
    (package / "other.py").write_text(
        "from houseq.room.inner import Thing\nfrom houseq.room.deep.leaf import X\n"
        "from houseq.room.port import OPENS\n"
    )
    (package / "room" / "inner.py").write_text("from houseq.room.deep.leaf import X\n")
    assert check([]) == [
        ("houseq.other", "houseq.room.deep.leaf"),
        ("houseq.other", "houseq.room.inner"),
        ("houseq.other", "houseq.room.port"),
    ]


def _layered(layers: list[str]) -> set[str]:
    return {
        name.strip() for layer in layers for group in layer.split("|") for name in group.split(":")
    }


def test_the_layers_contract_names_every_top_level_module_of_gonio() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    layers = next(c for c in config["contracts"] if c["name"] == "The layers")["layers"]
    gonio = ROOT / "gonio"
    modules = {
        f"gonio.{p.stem if p.is_file() else p.name}"
        for p in gonio.iterdir()
        if (p.suffix == ".py" and p.stem not in ("__init__", "__main__"))
        or (p / "__init__.py").is_file()
    }
    assert modules - _layered(layers) == set()


def test_every_name_of_every_face_resolves() -> None:
    """Each name a package's ``__all__`` offers is there when read, lazy ones from the
    module their ``WHERE`` names (a name moved to another module and left in ``WHERE``
    would fail only when first used)."""
    missing = []
    for root in (gonio, drivers, sim):
        for info in pkgutil.walk_packages(root.__path__, f"{root.__name__}."):
            if info.ispkg:
                face = importlib.import_module(info.name)
                missing += [
                    f"{info.name}.{n}" for n in face.__all__ if not hasattr(face, n)
                ]  # fmt: skip
    assert not missing
