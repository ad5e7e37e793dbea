"""A package's face whose names load with their module when first used (PEP 562), so
importing one inner module (``gonio.acquire.recovery``, ``gonio.planner.stored``) runs
the package's ``__init__`` without importing every other module it names: a ``gonio
info`` loads neither the engine nor the planner's samplers (scipy.stats, numba).

A face lists its names by module once (``WHERE``), imports them under
``typing.TYPE_CHECKING`` for the type checker (which sees those imports, not the
``__getattr__``: a misspelt name stays an error) and otherwise sets ``__getattr__,
__dir__ = lazy_face(__name__, WHERE)``; ``__all__`` is ``list(WHERE)``, or holds
``*WHERE`` beside the names the face binds eagerly.

Other packages import a package through its face (the faces contract of pyproject.toml,
``tools/faces_contract.py``), so its modules may move: a moved name moves in ``WHERE``."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any


def lazy_face(
    package: str, where: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``, whose name ``n`` is ``n`` of its
    module ``where[n]`` (a name relative to the package), imported on first use and kept;
    a name mapped to itself (``where["merl"] == "merl"``) is that module, a namespace (a
    name of the same name as its module, ``fit`` of ``fit``, is bound eagerly instead)."""

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = importlib.import_module(f"{package}.{module}")
        if module != name:  # a name of the module, else the module itself (a namespace)
            value = getattr(value, name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *where})

    return __getattr__, __dir__
