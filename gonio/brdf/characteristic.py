"""The test functions of Barla, Belcour & Pacanowski 2015, one BRDF effect each.

With h = (wi + wo)/2 (not normalized) and h̄ its projection on the tangent plane:

    fresnel_test_function    F = 1 − cos θd,   cos θd = wi · ĥ = ‖wi + wo‖/2
    specular_test_function   S = 1 − ‖h̄‖       (after Löw et al. 2012)
    grazing_test_function    G = 1 − (wi · n)(wo · n)

They are dimensionless, in [0, 1], and are evaluated like BRDFs (read as sr⁻¹)
so that the planner and the parametrization studies can sample them. They are not
physically based (no energy conservation is implied); all are reciprocal and
isotropic, and take no parameters.
"""

from __future__ import annotations

import numpy as np

from gonio.brdf.base import BRDF
from gonio.brdf.geometry import Pair
from gonio.types import FloatArray


class _TestFunction(BRDF):
    physically_based = False

    def __init__(self) -> None:
        super().__init__({})


class FresnelTestFunction(_TestFunction):
    """F = 1 − cos θd (white in figure 2 of Barla, Belcour & Pacanowski 2015)."""

    name = "fresnel_test_function"

    def _eval(self, p: Pair) -> FloatArray:
        return 1.0 - p.cos_theta_d()


class SpecularTestFunction(_TestFunction):
    """S = 1 − ‖h̄‖, h = (wi + wo)/2 (red in Barla et al.'s figure 2)."""

    name = "specular_test_function"

    def _eval(self, p: Pair) -> FloatArray:
        hx, hy = 0.5 * (p.xi + p.xo), 0.5 * (p.yi + p.yo)
        return np.asarray(1.0 - np.minimum(np.sqrt(hx * hx + hy * hy), 1.0), dtype=np.float64)


class GrazingTestFunction(_TestFunction):
    """G = 1 − (wi · n)(wo · n) (blue in Barla et al.'s figure 2).

    G = 1 where either direction is grazing (Barla et al. call this its "0-isoline":
    it is the product (wi · n)(wo · n) that is 0 there) and 0 only at wi = wo = n.
    """

    name = "grazing_test_function"

    def _eval(self, p: Pair) -> FloatArray:
        return np.asarray(1.0 - p.zi * p.zo, dtype=np.float64)
