"""The reconstruction methods by name: ``naive`` (the reference grid,
`gonio.reconstruct.naive`) and those of `gonio.reconstruct.build` where it is installed
(``linear``, ``rbf``, ``grid``, ``model+residual``)."""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import TYPE_CHECKING

from gonio.errors import GonioError

if TYPE_CHECKING:
    from gonio.reconstruct.measured import Measured
    from gonio.reconstruct.truth import Candidate

#: The method of the naive reference (`gonio.reconstruct.naive`); the others are
#: `gonio.reconstruct.build`'s.
NAIVE = "naive"
DEFAULT_METHOD = "linear"


def _build() -> ModuleType | None:
    """`gonio.reconstruct.build`, or None where this gonio does not have it."""
    try:
        return importlib.import_module("gonio.reconstruct.build")
    except ModuleNotFoundError as exc:
        if exc.name != "gonio.reconstruct.build":
            raise
        return None


def names() -> tuple[str, ...]:
    """Every method this gonio reconstructs with, ``naive`` first."""
    build = _build()
    return (NAIVE, *(() if build is None else tuple(build.METHODS)))


def check(method: str) -> None:
    """`GonioError` (one line) unless ``method`` names a reconstruction."""
    if method == NAIVE:
        return
    if _build() is None:
        raise GonioError(
            f"method {method!r} is not available: this gonio reconstructs only with {NAIVE!r}"
        )
    if method not in names():
        raise GonioError(f"unknown method {method!r}; expected one of {', '.join(names())}")


def reconstruction(measured: Measured, method: str, parametrization: str | None) -> Candidate:
    """The reconstruction of ``measured`` by ``method`` in ``parametrization`` (None:
    the run's); `GonioError` if there is no such method."""
    check(method)
    if method == NAIVE:
        from gonio.reconstruct.naive import NaiveReconstruction

        return NaiveReconstruction(measured, parametrization=parametrization)
    build = _build()
    assert build is not None
    result: Candidate = build.reconstruct(measured, method=method, parametrization=parametrization)
    return result
