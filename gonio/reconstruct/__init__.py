"""Reconstruction of a measured BRDF from a run's samples (docs/reconstruction.md), and
its evaluation against a truth (docs/evaluation.md): ``evaluate(candidate, truth, rig,
isotropic=…)``."""

from gonio.reconstruct.evaluate import Evaluation, evaluate

__all__ = ["Evaluation", "evaluate"]
