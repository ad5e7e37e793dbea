"""Inverse kinematics in the true geometry: the commanded angles `Rig.solve` gives a
misaligned rig measure the target pair (to ~1e-12) through `Rig.forward` with the
alignment, inside the limits and outside the keep-out boxes; with no alignment every
answer is the rig file's, bit for bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.rig import Alignment, Reason, Rig
from gonio.rig.alignment_spec import MAX_ERROR_DEG, MAX_HEIGHT_MM
from tests.conftest import ARCH_POINT_FILE, RIG_FILES

RIGS = {
    "arch": Rig.from_yaml(RIG_FILES["arch"]),
    "in_plane": Rig.from_yaml(RIG_FILES["in_plane"]),
    "arch_point": Rig.from_yaml(ARCH_POINT_FILE),
}
ERROR = np.radians(MAX_ERROR_DEG)


def pairs(seed: int, n: int = 300) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    z = rng.uniform(0.05, 1.0, (2, n))
    phi = rng.uniform(0.0, 2.0 * np.pi, (2, n))
    r = np.sqrt(1.0 - z * z)
    w = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
    return w[0], w[1]


def alignment(seed: int, scale: float) -> Alignment:
    rng = np.random.default_rng(seed)
    return Alignment(
        zero_offset=scale * rng.uniform(-ERROR, ERROR, 4),
        tilt=scale * rng.uniform(0.0, ERROR),
        tilt_azimuth=rng.uniform(-np.pi, np.pi),
        height_mm=scale * rng.uniform(-MAX_HEIGHT_MM, MAX_HEIGHT_MM),
        light_pointing=scale * rng.uniform(-ERROR, ERROR, 2),
        detector_pointing=scale * rng.uniform(-ERROR, ERROR, 2),
    )


def shift_bound(a: Alignment) -> float:
    """An upper bound (rad) on how far the alignment moves a joint angle that measures a
    given pair: every angular error added up, the height seen from a 100 mm arm."""
    angles = np.concatenate(
        [np.abs(a.zero_offset), np.abs(a.light_pointing), np.abs(a.detector_pointing)]
    )
    return float(angles.sum() + abs(a.tilt) + abs(a.height_mm) / 100.0)


@settings(max_examples=40, deadline=None)
@given(
    st.sampled_from(sorted(RIGS)),
    st.integers(0, 2**32 - 1),
    st.sampled_from([0.1, 0.5, 1.0]),
    st.booleans(),
)
def test_the_commanded_angles_measure_the_pair_in_the_true_geometry(
    name: str, seed: int, scale: float, isotropic: bool
) -> None:
    nominal = RIGS[name]
    rig = nominal.with_alignment(alignment(seed, scale))
    wi, wo = pairs(seed)
    s = rig.solve(wi, wo, isotropic=isotropic)
    ok = s.ok
    lost = nominal.solve(wi, wo, isotropic=isotropic)
    lost_ok = lost.ok & ~ok
    # A pair the rig file reaches is lost only to a limit or a keep-out box that its pose
    # lay within the misalignment of (some pose that near it cannot be commanded), or
    # about the pole of the detector's azimuth axis: a pointing error across the arc
    # leaves a cone about that pole that no azimuth reaches.
    reasons = (Reason.AXIS_LIMIT, Reason.THETA_MAX, Reason.COLLISION)
    assert np.all(np.isin(s.reasons[lost_ok], reasons))
    bound = 2.0 * shift_bound(rig.alignment)
    q0 = lost.angles[lost_ok]
    corners = np.stack(np.meshgrid(*[[-1.0, 0.0, 1.0]] * 4, indexing="ij"), -1).reshape(-1, 4)
    _, commandable = nominal.pose_reasons((q0[:, None, :] + bound * corners).reshape(-1, 4))
    near_limit = ~commandable.reshape(len(q0), len(corners)).all(axis=1)
    near_pole = np.zeros(len(q0), dtype=np.bool_)
    if "detector_azimuth" in nominal.axes:
        near_pole = np.abs(q0[:, nominal.axes.index("detector_elevation")]) <= bound
    assert np.all(near_limit | near_pole)
    q = s.angles[ok]
    ai, ao = rig.forward(q, rig.alignment)
    if isotropic:  # the pair turned about the true normal: what a turn keeps
        ti, to = wi[ok], wo[ok]
        np.testing.assert_allclose(ai[:, 2], ti[:, 2], rtol=0, atol=1e-12)
        np.testing.assert_allclose(ao[:, 2], to[:, 2], rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            np.sum(ai * ao, axis=1), np.sum(ti * to, axis=1), rtol=0, atol=1e-12
        )
    else:
        np.testing.assert_allclose(ai, wi[ok], rtol=0, atol=1e-12)
        np.testing.assert_allclose(ao, wo[ok], rtol=0, atol=1e-12)
    # The pair the solution reports is the one measured; the angles are commandable.
    assert np.array_equal(s.wi[ok], ai) and np.array_equal(s.wo[ok], ao)
    _, commandable = rig.pose_reasons(q)
    assert commandable.all()
    assert np.all(q >= rig.limits[:, 0]) and np.all(q <= rig.limits[:, 1])


def test_zero_offsets_and_tilt_are_solved_exactly() -> None:
    rig = RIGS["arch"]
    a = Alignment(zero_offset=np.radians([0.5, -0.3, 0.2, 1.0]), tilt=0.02, tilt_azimuth=0.7)
    aligned = rig.with_alignment(a)
    wi, wo = pairs(3)
    s = aligned.solve(wi, wo)
    ai, ao = aligned.forward(s.angles[s.ok], a)
    np.testing.assert_allclose(ai, wi[s.ok], rtol=0, atol=1e-14)
    np.testing.assert_allclose(ao, wo[s.ok], rtol=0, atol=1e-14)


def test_no_alignment_is_the_rig_files_solution_bit_for_bit() -> None:
    for rig in RIGS.values():
        none = rig.with_alignment(Alignment.none())
        wi, wo = pairs(5)
        for isotropic in (False, True):
            a, b = rig.solve(wi, wo, isotropic=isotropic), none.solve(wi, wo, isotropic=isotropic)
            for field in ("angles", "wi", "wo", "reasons", "candidates", "usable"):
                assert np.array_equal(getattr(a, field), getattr(b, field))
