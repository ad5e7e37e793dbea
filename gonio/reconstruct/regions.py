"""The regions of direction-pair space that fits and evaluations report separately.

Every pair falls in exactly one region, taken in the order of `NAMES`:

    grazing   θi or θo above `GRAZING_DEG` (whatever else holds)
    mirror    wo within `MIRROR_DEG` of the mirror direction of wi (the specular peak)
    retro     wo within `RETRO_DEG` of wi (retro-reflection; at normal incidence the
              mirror and retro directions coincide and the pair counts as mirror)
    rest      every other pair

Directions are unit vectors (..., 3) in the sample frame (z = normal), pointing away
from the surface (docs/explanations/conventions.md). The thresholds live here only.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.brdf import pair
from gonio.types import ArrayLike, BoolArray

#: Region names, in the order a pair is assigned to the first that holds it.
NAMES: tuple[str, ...] = ("grazing", "mirror", "retro", "rest")
#: Largest angle (degrees) between wo and the mirror direction of wi in "mirror".
MIRROR_DEG = 10.0
#: Largest angle (degrees) between wo and wi in "retro".
RETRO_DEG = 10.0
#: Polar angle (degrees) beyond which a direction is grazing.
GRAZING_DEG = 70.0


def regions(wi: ArrayLike, wo: ArrayLike) -> dict[str, BoolArray]:
    """One mask of shape broadcast(wi, wo)[:-1] per name of `NAMES`; the masks are
    disjoint and cover every pair."""
    p = pair(wi, wo)
    near_mirror = p.cos_psi() >= math.cos(math.radians(MIRROR_DEG))
    near_retro = p.dot() >= math.cos(math.radians(RETRO_DEG))
    cos_grazing = math.cos(math.radians(GRAZING_DEG))
    grazing = (p.zi < cos_grazing) | (p.zo < cos_grazing)
    masks: dict[str, BoolArray] = {}
    taken = np.zeros(p.shape, dtype=bool)
    for name, hit in zip(NAMES, (grazing, near_mirror, near_retro), strict=False):
        masks[name] = np.asarray(hit & ~taken, dtype=bool)
        taken = taken | hit
    masks["rest"] = np.asarray(~taken, dtype=bool)
    return masks
