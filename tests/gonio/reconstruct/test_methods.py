"""The reconstruction methods by name: naive and build's methods; model+residual fits
its model first; an unknown name is one line."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.analysis.measured import Measured
from gonio.errors import GonioError
from gonio.reconstruct import methods
from gonio.reconstruct.build import METHODS
from gonio.reconstruct.naive import NaiveReconstruction


def test_the_names_are_naive_then_builds() -> None:
    assert methods.names() == (methods.NAIVE, *METHODS)
    assert methods.DEFAULT_METHOD in METHODS
    for name in methods.names():
        methods.check(name)
    with pytest.raises(GonioError, match="unknown method 'cubic'; expected one of naive, linear"):
        methods.check("cubic")


def test_each_name_builds_its_reconstruction(matte_iso: Measured) -> None:
    naive = methods.reconstruction(matte_iso, "naive", None)
    assert isinstance(naive, NaiveReconstruction)
    linear = methods.reconstruction(matte_iso, "linear", "spherical")
    assert (linear.method, linear.parametrization) == ("linear", "spherical")  # type: ignore[attr-defined]


def test_model_plus_residual_fits_its_model_first(matte_iso: Measured) -> None:
    """The fitted lambert+ggx carries the shape: the reconstruction is its model times
    an interpolated ratio, which returns the samples at the samples."""
    r = methods.reconstruction(matte_iso, "model+residual", None)
    assert r.method == "model+residual"  # type: ignore[attr-defined]
    got = r.eval(matte_iso.wi[:200], matte_iso.wo[:200])
    np.testing.assert_allclose(got, matte_iso.f[:200], rtol=1e-6)
