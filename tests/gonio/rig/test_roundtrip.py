"""FK∘IK and IK∘FK round trips of the shipped rigs, to 1e-10 rad.

FK∘IK: for a pair (ωi, ωo), every closed-form candidate and the chosen solution give
back (ωi, ωo) under forward kinematics; the chosen solution of a reachable pair is also
inside the axes' limits and out of the keep-out boxes.

IK∘FK: for joint angles q inside the limits, one of the candidates for FK(q) is q itself
(joint by joint; modulo 2π only on multi-turn axes, whose range spans more than a turn).
Where the pose is singular the candidates cannot tell poses apart (the arch at zero
elevation: the azimuth is free; the in-plane rig with the two arms on one line: the
plane is free), and near it they are ill-conditioned (an error ε/s at distance s), so
the joint-by-joint check is made where the pose is 1e-3 rad away from a singularity
(more than 99 % of random poses); FK of every candidate reproduces the directions for
every pose.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from gonio.types import BoolArray, FloatArray
from tests.conftest import RIG_NAMES
from tests.gonio.rig.helpers import TOL, column, wrap
from tests.support.rigs import angle_between, direction, uniform_directions

BATCH = 20_000
#: Distance (rad) from a singular pose beyond which joint angles must round-trip.
SINGULAR_MARGIN = 1e-3


def fk_error(rig: Rig, angles: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
    """Angle (rad) between FK(angles) and the pair, the worse of ωi and ωo."""
    fi, fo = rig.forward(angles)
    return np.maximum(angle_between(fi, wi), angle_between(fo, wo))


def joint_error(rig: Rig, candidates: FloatArray, pose: FloatArray) -> FloatArray:
    """(N,) the smallest, over the candidates (N, K, A), of the largest joint difference
    from ``pose`` (N, A); modulo 2π on multi-turn axes only."""
    diff = candidates - pose[:, None, :]
    multi_turn = (rig.limits[:, 1] - rig.limits[:, 0]) >= 2.0 * np.pi
    diff[..., multi_turn] = wrap(diff[..., multi_turn])
    return np.asarray(np.abs(diff).max(axis=-1).min(axis=-1), dtype=np.float64)


def well_conditioned(rig: Rig, pose: FloatArray) -> BoolArray:
    """Poses at least SINGULAR_MARGIN away from the rig type's singular poses."""
    if rig.spec.type == "arch":
        light = np.abs(pose[..., column(rig, "light_elevation")])
        detector = np.abs(pose[..., column(rig, "detector_elevation")])
        return np.asarray(np.minimum(light, detector) >= SINGULAR_MARGIN, dtype=np.bool_)
    between = pose[..., column(rig, "detector_arm")] - pose[..., column(rig, "light_arm")]
    return np.asarray(np.abs(np.sin(between)) >= SINGULAR_MARGIN, dtype=np.bool_)


def within_limits(rig: Rig, angles: FloatArray) -> BoolArray:
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    return np.asarray(np.all((angles >= lo) & (angles <= hi), axis=-1), dtype=np.bool_)


def in_keep_out(rig: Rig, angles: FloatArray) -> BoolArray:
    hit = np.zeros(angles.shape[:-1], dtype=np.bool_)
    for box in rig.spec.constraints.collisions:
        inside = np.ones(angles.shape[:-1], dtype=np.bool_)
        for name, (lo, hi) in box.ranges_deg.items():
            value = np.degrees(angles[..., column(rig, name)])
            inside &= (value >= lo) & (value <= hi)
        hit |= inside
    return hit


# -- seeded batches ----------------------------------------------------------------------
def test_fk_of_ik_batch(rig: Rig) -> None:
    rng = np.random.default_rng(20_240_601)
    wi = uniform_directions(rng, BATCH, rig.theta_max)
    wo = uniform_directions(rng, BATCH, rig.theta_max)
    solution = rig.solve(wi, wo)
    ok = solution.ok
    assert ok.mean() > 0.5  # the batch does test reachable pairs
    assert fk_error(rig, solution.angles[ok], wi[ok], wo[ok]).max() <= TOL
    assert within_limits(rig, solution.angles[ok]).all()
    assert not in_keep_out(rig, solution.angles[ok]).any()
    # Every candidate, usable or not, is an exact solution.
    assert fk_error(rig, solution.candidates, wi[:, None], wo[:, None]).max() <= TOL


def test_ik_of_fk_batch(rig: Rig) -> None:
    rng = np.random.default_rng(7)
    pose = rng.uniform(rig.limits[:, 0], rig.limits[:, 1], (BATCH, len(rig.axes)))
    wi, wo = rig.forward(pose)
    candidates, _ = rig.candidates(wi, wo)
    assert fk_error(rig, candidates, wi[:, None], wo[:, None]).max() <= TOL
    regular = well_conditioned(rig, pose)
    assert regular.mean() > 0.99
    assert joint_error(rig, candidates[regular], pose[regular]).max() <= TOL


def test_ik_of_fk_is_ill_posed_at_a_singular_pose(rigs: dict[str, Rig]) -> None:
    """The reason for SINGULAR_MARGIN: with the arch's light at the zenith, a pose and the
    same pose with the sample and the arch turned together give the same pair."""
    rig = rigs["arch"]
    pose = np.radians([0.0, 30.0, 40.0, 50.0])
    turned = pose + np.radians([0.0, 20.0, 0.0, 20.0])
    for a, b in zip(rig.forward(pose), rig.forward(turned), strict=True):
        assert angle_between(a, b) <= TOL


# -- hypothesis --------------------------------------------------------------------------
HALF_PI = float(np.pi / 2)
polar = st.one_of(
    st.floats(0.0, HALF_PI),
    st.sampled_from([0.0, HALF_PI]),
    st.floats(-12.0, -2.0).map(lambda e: HALF_PI - 10.0**e),
    st.floats(-12.0, -2.0).map(lambda e: 10.0**e),
)
azimuth = st.floats(0.0, 2.0 * np.pi, exclude_max=True)


def rotated(w: FloatArray, towards: FloatArray, angle: float) -> FloatArray:
    """``w`` turned by ``angle`` about an axis perpendicular to it (through ``towards``)."""
    k = np.cross(w, towards)
    if np.linalg.norm(k) < 1e-6:
        k = np.cross(w, [1.0, 0.0, 0.0] if abs(w[0]) < 0.9 else [0.0, 1.0, 0.0])
    k /= np.linalg.norm(k)
    return np.asarray(
        w * np.cos(angle) + np.cross(k, w) * np.sin(angle) + k * (k @ w) * (1 - np.cos(angle)),
        dtype=np.float64,
    )


@st.composite
def pairs(draw: st.DrawFn) -> tuple[FloatArray, FloatArray]:
    """Pairs over the closed hemisphere, often at an extreme: normal incidence, grazing,
    retro-reflection (exact or within 1e-16 … 1e-1 rad), mirror, opposite azimuths."""
    wi = direction(np.degrees(draw(polar)), np.degrees(draw(azimuth)))
    kind = draw(st.sampled_from(["free", "retro", "near", "mirror"]))
    if kind == "retro":
        return wi, wi.copy()
    if kind == "mirror":
        return wi, wi * np.array([-1.0, -1.0, 1.0])
    other = direction(np.degrees(draw(polar)), np.degrees(draw(azimuth)))
    if kind == "free":
        return wi, other
    return wi, rotated(wi, other, 10.0 ** draw(st.floats(-16.0, -1.0)))


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(RIG_NAMES), pair=pairs())
def test_fk_of_ik_any_pair(
    rigs: dict[str, Rig], name: str, pair: tuple[FloatArray, FloatArray]
) -> None:
    rig = rigs[name]
    wi, wo = pair[0][None], pair[1][None]
    solution = rig.solve(wi, wo)
    assert fk_error(rig, solution.candidates, wi[:, None], wo[:, None]).max() <= TOL
    if solution.ok[0]:
        assert fk_error(rig, solution.angles, wi, wo)[0] <= TOL
        assert within_limits(rig, solution.angles)[0]


@st.composite
def poses(draw: st.DrawFn, rig: Rig) -> FloatArray:
    return np.array([draw(st.floats(lo, hi)) for lo, hi in rig.limits])


@settings(max_examples=150, deadline=None)
@given(data=st.data(), name=st.sampled_from(RIG_NAMES))
def test_ik_of_fk_any_pose(rigs: dict[str, Rig], data: st.DataObject, name: str) -> None:
    rig = rigs[name]
    pose = data.draw(poses(rig))[None]
    wi, wo = rig.forward(pose)
    candidates, _ = rig.candidates(wi, wo)
    assert fk_error(rig, candidates, wi[:, None], wo[:, None]).max() <= TOL
    if well_conditioned(rig, pose)[0]:
        assert joint_error(rig, candidates, pose)[0] <= TOL


@pytest.mark.parametrize("apart", [1e-15, 1e-13, 1e-12, 1e-11, 1e-9, 1e-7, 1e-5, 1e-3])
def test_candidates_exact_near_retro_reflection(rig: Rig, apart: float) -> None:
    """Regression: the in-plane solver took the plane's normal from ωi × ωo, which keeps
    only ε/|ωi × ωo| relative precision (FK 4e-5 rad off at 1e-12 rad apart)."""
    rng = np.random.default_rng(3)
    wi = uniform_directions(rng, 200, np.radians(85.0))
    wo = np.array(
        [rotated(w, t, apart) for w, t in zip(wi, uniform_directions(rng, 200, 1.5), strict=True)]
    )
    candidates, _ = rig.candidates(wi, wo)
    assert fk_error(rig, candidates, wi[:, None], wo[:, None]).max() <= TOL


def test_reachable_pairs_are_solved_exactly_named(rigs: dict[str, Rig]) -> None:
    """A named reachable pair per rig, refused for nothing, round-trips."""
    for rig in rigs.values():
        wi, wo = direction(30.0, 20.0)[None], direction(50.0, 200.0)[None]
        solution = rig.solve(wi, wo)
        assert solution.reasons[0] == Reason.OK
        assert fk_error(rig, solution.angles, wi, wo)[0] <= TOL
