"""Reconstruction of a measured BRDF from a run's samples (docs/reconstruction.md).

``reconstruct(Measured.from_run(path), method=...)`` returns a `Reconstruction` with
``eval``, ``uncertainty`` and ``supported`` over direction pairs; `METHODS` lists the
interpolation methods.
"""

from gonio.reconstruct.build import METHODS, reconstruct
from gonio.reconstruct.measured import Measured
from gonio.reconstruct.result import Reconstruction

__all__ = ["METHODS", "Measured", "Reconstruction", "reconstruct"]
