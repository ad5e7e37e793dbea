"""The regions of pair space: a partition, with the documented thresholds."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from gonio.reconstruct.regions import GRAZING_DEG, MIRROR_DEG, NAMES, RETRO_DEG, regions


def _direction(theta_deg: float, phi_deg: float) -> np.ndarray:
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def _region(wi: np.ndarray, wo: np.ndarray) -> str:
    masks = regions(wi, wo)
    return next(name for name in NAMES if masks[name])


angles = st.floats(0.0, 90.0)
azimuths = st.floats(0.0, 360.0)


@given(angles, azimuths, angles, azimuths)
def test_every_pair_is_in_exactly_one_region(ti, pi, to, po):
    masks = regions(_direction(ti, pi), _direction(to, po))
    assert tuple(masks) == NAMES
    assert sum(bool(m) for m in masks.values()) == 1


def test_thresholds():
    wi = _direction(40.0, 0.0)
    assert _region(wi, _direction(40.0, 180.0)) == "mirror"
    assert _region(wi, _direction(40.0 + MIRROR_DEG - 0.5, 180.0)) == "mirror"
    assert _region(wi, _direction(40.0 + MIRROR_DEG + 0.5, 180.0)) == "rest"
    assert _region(wi, _direction(40.0 + RETRO_DEG - 0.5, 0.0)) == "retro"
    assert _region(wi, _direction(40.0 + RETRO_DEG + 0.5, 0.0)) == "rest"
    assert _region(wi, _direction(GRAZING_DEG + 0.5, 90.0)) == "grazing"
    assert _region(_direction(GRAZING_DEG + 0.5, 0.0), _direction(10.0, 90.0)) == "grazing"
    assert _region(_direction(0.0, 0.0), _direction(5.0, 0.0)) == "mirror"  # both hold


def test_masks_have_the_pairs_shape():
    wi = np.broadcast_to(_direction(30.0, 0.0), (4, 5, 3))
    masks = regions(wi, _direction(30.0, 180.0))
    assert all(m.shape == (4, 5) and m.dtype == bool for m in masks.values())
    assert masks["mirror"].all()
