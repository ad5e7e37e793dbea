"""Reconstruction of a measured BRDF from a run's samples (docs/explanations/reconstruction.md), and
its evaluation against a truth (docs/explanations/evaluation.md).

``reconstruct(gonio.analysis.Measured.from_run(path), method=...)`` returns a `Reconstruction` with
``eval``, ``uncertainty`` and ``supported`` over direction pairs; `METHODS` lists the
interpolation methods. ``evaluate(candidate, truth, rig, isotropic=…)`` scores any
candidate against a truth.
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.reconstruct.build import METHODS, reconstruct
from gonio.reconstruct.evaluate import Evaluation, evaluate
from gonio.reconstruct.fit import fit
from gonio.reconstruct.regions import regions
from gonio.reconstruct.result import Reconstruction

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.reconstruct import methods as methods
    from gonio.reconstruct import testset as testset
    from gonio.reconstruct import transforms as transforms
    from gonio.reconstruct.evaluate import DEFAULT_FILL as DEFAULT_FILL
    from gonio.reconstruct.fit import FitResult as FitResult
    from gonio.reconstruct.methods import DEFAULT_METHOD as DEFAULT_METHOD
    from gonio.reconstruct.methods import FILLS as FILLS
    from gonio.reconstruct.methods import NAIVE as NAIVE
    from gonio.reconstruct.methods import names as names
    from gonio.reconstruct.methods import reconstruction as reconstruction
    from gonio.reconstruct.metrics import METRICS as METRICS
    from gonio.reconstruct.metrics import REGIONS as REGIONS
    from gonio.reconstruct.metrics import Scores as Scores
    from gonio.reconstruct.metrics import region_masks as region_masks
    from gonio.reconstruct.metrics import scores as scores
    from gonio.reconstruct.naive import NaiveReconstruction as NaiveReconstruction
    from gonio.reconstruct.regions import NAMES as NAMES
    from gonio.reconstruct.result import EVALUATION_BLOCK as EVALUATION_BLOCK
    from gonio.reconstruct.result import values_and_support as values_and_support
    from gonio.reconstruct.testset import DEFAULT_SEED as DEFAULT_SEED
    from gonio.reconstruct.testset import DEFAULT_SIZE as DEFAULT_SIZE
    from gonio.reconstruct.testset import TestSet as TestSet
    from gonio.reconstruct.truth import SCENE as SCENE
    from gonio.reconstruct.truth import Candidate as Candidate
    from gonio.reconstruct.truth import Truth as Truth
    from gonio.reconstruct.truth import truth_from_spec as truth_from_spec

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Candidate": "truth",
    "DEFAULT_FILL": "evaluate",
    "DEFAULT_METHOD": "methods",
    "DEFAULT_SEED": "testset",
    "DEFAULT_SIZE": "testset",
    "EVALUATION_BLOCK": "result",
    "FILLS": "methods",
    "FitResult": "fit",
    "METRICS": "metrics",
    "NAIVE": "methods",
    "NAMES": "regions",
    "NaiveReconstruction": "naive",
    "REGIONS": "metrics",
    "SCENE": "truth",
    "Scores": "metrics",
    "TestSet": "testset",
    "Truth": "truth",
    "methods": "methods",
    "names": "methods",
    "reconstruction": "methods",
    "region_masks": "metrics",
    "scores": "metrics",
    "testset": "testset",
    "transforms": "transforms",
    "truth_from_spec": "truth",
    "values_and_support": "result",
}
__all__ = [
    "Evaluation",
    "METHODS",
    "Reconstruction",
    "evaluate",
    "fit",
    "reconstruct",
    "regions",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
