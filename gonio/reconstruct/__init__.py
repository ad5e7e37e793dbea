"""Reconstruction of a measured BRDF from a run's samples (docs/explanations/reconstruction.md), and
its evaluation against a truth (docs/explanations/evaluation.md).

``reconstruct(gonio.analysis.Measured.from_run(path), method=...)`` returns a `Reconstruction` with
``eval``, ``uncertainty`` and ``supported`` over direction pairs; `METHODS` lists the
interpolation methods. ``evaluate(candidate, truth, rig, isotropic=…)`` scores any
candidate against a truth.
"""

from gonio.reconstruct.build import METHODS, reconstruct
from gonio.reconstruct.evaluate import Evaluation, evaluate
from gonio.reconstruct.result import Reconstruction

__all__ = ["METHODS", "Evaluation", "Reconstruction", "evaluate", "reconstruct"]
