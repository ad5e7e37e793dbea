"""Array type aliases shared by the math modules."""

from collections.abc import Callable
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

FloatArray: TypeAlias = npt.NDArray[np.float64]
BoolArray: TypeAlias = npt.NDArray[np.bool_]
ArrayLike: TypeAlias = npt.ArrayLike
#: A BRDF as a function: f(wi (..., 3), wo (..., 3)) in sr⁻¹ (`gonio.brdf.BRDF.eval`).
BrdfEval: TypeAlias = Callable[[FloatArray, FloatArray], FloatArray]
