"""The reconstruction methods by name: naive always, the others from
`gonio.reconstruct.build` where it exists; an unknown name is one line."""

from __future__ import annotations

import importlib.util

import pytest

from gonio.errors import GonioError
from gonio.reconstruct import methods


def test_naive_is_always_a_method_and_others_come_from_build() -> None:
    names = methods.names()
    assert names[0] == methods.NAIVE
    if importlib.util.find_spec("gonio.reconstruct.build") is None:
        assert names == (methods.NAIVE,)
        with pytest.raises(GonioError, match="'linear' is not available"):
            methods.check("linear")
    else:
        assert methods.DEFAULT_METHOD in names
        with pytest.raises(GonioError, match="unknown method 'cubic'; expected one of naive"):
            methods.check("cubic")
    methods.check(methods.NAIVE)
