"""Array type aliases shared by the math modules."""

from collections.abc import Callable
from typing import Protocol, TypeAlias

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
BoolArray: TypeAlias = npt.NDArray[np.bool_]
ArrayLike: TypeAlias = npt.ArrayLike
#: A BRDF as a function: f(wi (..., 3), wo (..., 3)) in sr⁻¹ (`gonio.brdf.BRDF.eval`).
BrdfEval: TypeAlias = Callable[[FloatArray, FloatArray], FloatArray]


class Evaluable(Protocol):
    """Anything giving f(ωi, ωo) in sr⁻¹ like `gonio.brdf.BRDF`: pairs (..., 3) → values
    (...,) or (..., 3) for RGB (an analytic model, a fitted one, a reconstruction)."""

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray: ...


class Surface(Evaluable, Protocol):
    """An `Evaluable` that knows where it is backed by measurements (a reconstruction)."""

    def supported(self, wi: FloatArray, wo: FloatArray) -> BoolArray: ...
