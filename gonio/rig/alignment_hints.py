"""Why a mirror scan leaves an alignment parameter undetermined, and what would
determine it (`hint`): by what the parameter does to the directions the rig measures,
probed at `PROBE_PAIRS` pairs spread over what it reaches (central differences of the
aligned forward map at no misalignment).

- A parameter that moves no measured direction needs no correcting (a height with a
  collimated beam and a distant detector).
- One whose effect on every direction is a combination of the others' is inseparable
  from them by any measurement of directions (an axis's zero offset and a pointing
  error about that axis): only what they do together matters, and the fit keeps the
  least-norm share of it.
- Otherwise another scan would determine it (`NEEDS`, by name prefix).
"""

from __future__ import annotations

import numpy as np

from gonio.rig.alignment import Alignment
from gonio.rig.model import Rig
from gonio.types import FloatArray

#: Direction pairs the rig is probed at.
PROBE_PAIRS = 256
#: Central-difference step (rad, mm) of the probe.
STEP = 1e-6
#: An effect below this (rad per unit, rms over the probe) moves no direction.
NONE = 1e-9
#: An effect within this share of the others' span is a combination of theirs (and
#: the relative singular value below which their combinations are not told apart).
SPANNED = 1e-6
#: A parameter that takes less than this share in such a combination is not named.
SHARE = 1e-3
#: What would determine a parameter a scan does not (by name prefix; the first that
#: matches).
NEEDS = {
    "zero_offset.sample_rotation": "an anisotropic reference (a grating, a brushed "
    "sample): a mirror looks the same at every turn of the stage",
    "zero_offset": "peaks at more poses of that axis",
    "tilt": "the same light poses at three or more sample rotations",
    "height_mm": "peaks over a wider range of incidences (a point source's direction moves "
    "by h sin θi / r)",
    "light_pointing": "peaks over a wider range of light elevations",
    "detector_pointing": "peaks over a wider range of detector poses",
}


def effects(rig: Rig, to_alignment: object, count: int) -> FloatArray:
    """(K, P): each parameter's effect on the measured directions (4 tangent-free
    components per direction pair, stacked) at `PROBE_PAIRS` reachable pairs, per unit
    (rad, mm). ``to_alignment``: the map of a parameter vector (P,) to an `Alignment`."""
    assert callable(to_alignment)
    rng = np.random.default_rng(0)
    z = rng.uniform(0.05, 1.0, (2, PROBE_PAIRS))
    phi = rng.uniform(0.0, 2.0 * np.pi, (2, PROBE_PAIRS))
    r = np.sqrt(1.0 - z * z)
    w = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
    solution = rig.solve(w[0], w[1])
    q = solution.angles[solution.ok]
    columns = []
    for k in range(count):
        e = np.zeros(count)
        e[k] = STEP
        up: Alignment = to_alignment(e)
        down: Alignment = to_alignment(-e)
        moved = [a - b for a, b in zip(rig.forward(q, up), rig.forward(q, down), strict=True)]
        columns.append(np.concatenate([m.ravel() for m in moved]) / (2.0 * STEP))
    return np.stack(columns, axis=1)


def hints(
    rig: Rig, names: tuple[str, ...], undetermined: list[str], to_alignment: object
) -> dict[str, str]:
    """Why each of the ``undetermined`` parameters is, and what would determine it (the
    module)."""
    columns = effects(rig, to_alignment, len(names))
    rms = np.sqrt(np.mean(columns**2, axis=0))
    out = {}
    for name in undetermined:
        k = names.index(name)
        if rms[k] < NONE:
            out[name] = "moves no direction this rig measures: nothing to correct"
            continue
        others = np.delete(columns, k, axis=1)
        fitted, *_ = np.linalg.lstsq(others, columns[:, k], rcond=SPANNED)
        left = np.linalg.norm(columns[:, k] - others @ fitted) / np.linalg.norm(columns[:, k])
        if left < SPANNED:
            alike = [
                n
                for n, c in zip(np.delete(np.array(names), k), fitted, strict=True)
                if abs(c) > SHARE
            ]
            out[name] = (
                f"no scan separates it from {' and '.join(alike)}: it moves every measured "
                f"direction as {'that does' if len(alike) == 1 else 'they do together'} "
                "(what they do together is fitted, and is what the directions need)"
            )
            continue
        need = next(h for prefix, h in NEEDS.items() if name.startswith(prefix))
        out[name] = f"needs {need}"
    return out
