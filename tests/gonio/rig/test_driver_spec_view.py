"""The type checker's view of a driver-made rig section (the ``if TYPE_CHECKING:``
classes of `gonio.rig.instrument` and `gonio.rig.lab_instrument`) declares only fields
the run-time model has, each with the model's annotation."""

from __future__ import annotations

import ast
import inspect
import typing
from types import ModuleType

import pytest

from gonio.rig import instrument, lab_instrument

#: (module, the type checker's base class, the spec built on it at run time).
VIEWS = [
    (instrument, "_StreamFields", instrument.SerialStreamSpec),
    (instrument, "_InterfaceFields", instrument.SerialInterfaceSpec),
    (lab_instrument, "_ExposureFields", lab_instrument.PyMeasureExposureSpec),
    (lab_instrument, "_InterfaceFields", lab_instrument.PyMeasureInterfaceSpec),
]


def _declared(module: ModuleType, name: str) -> dict[str, str]:
    """{field: annotation source} of class ``name`` under ``if TYPE_CHECKING:``."""
    tree = ast.parse(inspect.getsource(module))
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for cls in node.body:
                if isinstance(cls, ast.ClassDef) and cls.name == name:
                    return {
                        item.target.id: ast.unparse(item.annotation)
                        for item in cls.body
                        if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name)
                    }
    raise AssertionError(f"{module.__name__} declares no {name} for the type checker")


@pytest.mark.parametrize(
    ("module", "name", "spec"), VIEWS, ids=[v[1] + v[2].__name__ for v in VIEWS]
)
def test_declared_fields_are_the_models(module: ModuleType, name: str, spec: type) -> None:
    declared = _declared(module, name)
    namespace = {**vars(module), **vars(typing)}
    for field, source in declared.items():
        assert field in spec.model_fields, f"{name}.{field} is not a field of {spec.__name__}"
        assert eval(source, namespace) == spec.model_fields[field].annotation, field
