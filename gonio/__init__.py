"""gonio: a virtual gonioreflectometer with a hardware driver layer.

Subpackages: :mod:`gonio.params` (BRDF parametrizations), :mod:`gonio.brdf`
(analytic BRDF models). Conventions (frames, units, angles) are in
``docs/explanations/conventions.md``.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
