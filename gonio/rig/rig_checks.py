"""The checks a rig file passes beyond its schema, when the `Rig` is made: its chains
are those of its closed-form type (`check_chains`), and its constraints leave some of
the hemisphere measurable (`check_reachable`). Each failure is a one-line `ConfigError`
naming the rig file (``where``) and the field."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gonio.config import ConfigError
from gonio.rig.schema import RigSpec
from gonio.rig.solution import Reason
from gonio.types import FloatArray

#: What each closed-form type needs the chains to be: (axis name, rotation axis).
EXPECTED_CHAINS = {
    "arch": {
        "light": [("light_elevation", (0, 1, 0))],
        "detector": [("detector_azimuth", (0, 0, 1)), ("detector_elevation", (0, 1, 0))],
        "sample": [("sample_rotation", (0, 0, 1))],
    },
    "in_plane": {
        "light": [("light_arm", (0, 1, 0))],
        "detector": [("detector_arm", (0, 1, 0))],
        "sample": [("sample_tilt", (1, 0, 0)), ("sample_rotation", (0, 0, 1))],
    },
}
#: Direction pairs probed when a rig is loaded, to refuse a rig that can measure nothing.
PROBE_PAIRS = 4096
#: The first of them probed alone: one reachable pair ends the check, and a rig that can
#: measure anything reaches one of these (an aligned rig solves each pair by Newton
#: steps, 0.2 s of CPU for all 4096).
PROBE_FIRST = 64


def check_chains(spec: RigSpec, where: str) -> None:
    """`ConfigError` unless each chain's axes (and the light's and detector's pointing,
    along z) are those `EXPECTED_CHAINS` gives the rig's type."""
    for chain, expected in EXPECTED_CHAINS[spec.type].items():
        section = getattr(spec, chain)
        got = [(n, tuple(round(c, 9) for c in spec.axes[n].axis)) for n in section.axes]
        if got != [(n, tuple(float(c) for c in v)) for n, v in expected]:
            wanted = ", ".join(f"{n} about {v}" for n, v in expected)
            raise ConfigError(f"{where}: {chain}.axes: a {spec.type} rig needs {wanted}")
        if chain != "sample" and tuple(section.pointing) != (0.0, 0.0, 1.0):
            raise ConfigError(
                f"{where}: {chain}.pointing: a {spec.type} rig points along (0, 0, 1)"
            )


def check_reachable(
    reasons_of: Callable[[FloatArray, FloatArray, bool], np.ndarray], where: str
) -> None:
    """`ConfigError` if ``reasons_of(wi, wo, isotropic)`` (the `Reason` of each pair, as
    `Rig.solve` gives them) refuses every one of `PROBE_PAIRS` direction pairs spread
    over the hemisphere, anisotropic and isotropic (a rig that can measure nothing)."""
    rng = np.random.default_rng(0)
    z = rng.uniform(0.0, 1.0, (2, PROBE_PAIRS))
    phi = rng.uniform(0.0, 2.0 * np.pi, (2, PROBE_PAIRS))
    r = np.sqrt(1.0 - z * z)
    w = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
    for isotropic in (False, True):
        for n in (PROBE_FIRST, PROBE_PAIRS):  # each pair is solved on its own
            reasons = reasons_of(w[0, :n], w[1, :n], isotropic)
            if np.any(reasons == Reason.OK):
                return
    counts = ", ".join(
        f"{r.label.replace('_', ' ')} {n}"
        for r in Reason
        if r != Reason.OK and (n := int(np.count_nonzero(reasons == r)))
    )
    raise ConfigError(
        f"{where}: constraints: leave no direction pair measurable (of {PROBE_PAIRS} pairs "
        f"spread over the hemisphere, refused: {counts}); expected constraints that "
        "leave some of the hemisphere reachable"
    )
