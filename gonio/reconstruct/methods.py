"""The reconstruction methods by name, as commands and sweeps choose them: ``naive`` (the
reference grid, `gonio.reconstruct.naive`) and those of `gonio.reconstruct.build`
(``linear``, ``rbf``, ``grid``, ``model+residual``). For ``model+residual`` the model is
fitted to the samples first (`gonio.reconstruct.fit`, family `DEFAULT_MODEL` unless
another is named): the model carries the shape, the samples correct it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gonio.errors import UnknownNameError
from gonio.reconstruct.build import EXTRAPOLATIONS, METHODS, reconstruct
from gonio.reconstruct.fit import fit
from gonio.reconstruct.naive import NaiveReconstruction

if TYPE_CHECKING:
    from gonio.analysis import Measured
    from gonio.types import Surface

#: The method of the naive reference (`gonio.reconstruct.naive`).
NAIVE = "naive"
DEFAULT_METHOD = "linear"
#: The family fitted for ``model+residual`` unless another is named (docs/explanations/fitting.md).
DEFAULT_MODEL = "lambert+ggx"
#: The fills a command may name (`gonio.reconstruct.build.EXTRAPOLATIONS` less none).
FILLS = tuple(e for e in EXTRAPOLATIONS if e is not None)


def names() -> tuple[str, ...]:
    """Every method, ``naive`` first."""
    return (NAIVE, *METHODS)


def check(method: str) -> None:
    """`UnknownNameError` (one line) unless ``method`` names a reconstruction."""
    if method not in names():
        raise UnknownNameError(f"unknown method {method!r}; expected one of {', '.join(names())}")


def reconstruction(
    measured: Measured,
    method: str,
    parametrization: str | None,
    *,
    model: str = DEFAULT_MODEL,
    extrapolate: str | None = None,
) -> Surface:
    """The reconstruction of ``measured`` by ``method`` in ``parametrization`` (None:
    the run's); ``model``: the family ``model+residual`` fits (a `gonio fit` SPEC);
    ``extrapolate``: how a build method fills pairs outside the measured support
    (`gonio.reconstruct.build.EXTRAPOLATIONS`; the naive grid always fills by its
    nearest node)."""
    check(method)
    if method == NAIVE:
        return NaiveReconstruction(measured, parametrization=parametrization)
    fitted = None
    if method == "model+residual":
        fitted = fit(measured, model).model
    result: Surface = reconstruct(
        measured,
        method=method,
        parametrization=parametrization,
        model=fitted,
        extrapolate=extrapolate,
    )
    return result
