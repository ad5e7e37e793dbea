"""The misalignment's forward map (`gonio.rig.alignment` through `Rig.forward`): the
identity when none, bit for bit; a zero offset is commanding the axis shifted; a
sample tilt α moves a mirror's specular peak by 2α; a pointing error about the last
axis is that axis's zero offset; first-order linearity in every parameter; batches of
alignments over leading axes; finite values at the bounds' extremes; the height's
spot shifts and a point source's true direction."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.rig import Alignment, Rig
from gonio.rig.alignment_spec import MAX_ERROR_DEG, MAX_HEIGHT_MM, AlignmentSpec
from gonio.types import FloatArray
from tests.conftest import ARCH_POINT_FILE, RIG_FILES
from tests.support.rigs import angle_between

RIGS = {name: Rig.from_yaml(path) for name, path in RIG_FILES.items()}
RIGS["arch_point"] = Rig.from_yaml(ARCH_POINT_FILE)
NAMES = st.sampled_from(sorted(RIGS))
SEEDS = st.integers(0, 2**32 - 1)
EPS = math.radians(MAX_ERROR_DEG)


def poses(rig: Rig, rng: np.random.Generator, n: int = 64) -> FloatArray:
    """Joint angles (n, A) inside the limits, the limits themselves among them."""
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    q = rng.uniform(lo, hi, (n, len(rig.axes)))
    q[0], q[1] = lo, hi
    return q


def random_alignment(rig: Rig, rng: np.random.Generator, scale: float) -> Alignment:
    """Every parameter drawn in [−scale, scale] (rad; the height in mm × 10)."""
    u = lambda *shape: rng.uniform(-scale, scale, shape)  # noqa: E731
    return Alignment(
        zero_offset=u(len(rig.axes)),
        tilt=abs(float(u(1)[0])),
        tilt_azimuth=rng.uniform(-np.pi, np.pi),
        height_mm=10.0 * float(u(1)[0]),
        light_pointing=u(2),
        detector_pointing=u(2),
    )


@given(NAMES, SEEDS)
@settings(max_examples=20, deadline=None)
def test_none_is_the_rig_file_bit_for_bit(name: str, seed: int) -> None:
    rig = RIGS[name]
    q = poses(rig, np.random.default_rng(seed))
    plain = rig.forward(q)
    for alignment in (Alignment.none(), AlignmentSpec().alignment(rig.axes)):
        assert alignment.is_none
        got = rig.forward(q, alignment)
        assert all(np.array_equal(a, b) for a, b in zip(got, plain, strict=True))


@given(NAMES, SEEDS, st.floats(-EPS, EPS), st.data())
@settings(max_examples=40, deadline=None)
def test_a_zero_offset_is_commanding_the_axis_shifted(
    name: str, seed: int, delta: float, data: st.DataObject
) -> None:
    rig = RIGS[name]
    j = data.draw(st.integers(0, len(rig.axes) - 1))
    q = poses(rig, np.random.default_rng(seed))
    offset = np.zeros(len(rig.axes))
    offset[j] = delta
    shifted = q.copy()
    shifted[:, j] += delta
    for got, want in zip(
        rig.forward(q, Alignment(zero_offset=offset)), rig.forward(shifted), strict=True
    ):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


@given(st.floats(5.0, 80.0), st.floats(-MAX_ERROR_DEG, MAX_ERROR_DEG), st.floats(-180, 180))
@settings(max_examples=60, deadline=None)
def test_a_tilt_moves_a_mirrors_specular_peak_by_twice_its_angle(
    light_deg: float, tilt_deg: float, rotation_deg: float
) -> None:
    """Arch rig, the tilt toward the light (its azimuth the stage's, turned with it): the
    mirror reflects ωi into ωo with the detector 2α off the rig file's specular pose."""
    rig = RIGS["arch"]
    theta, alpha, psi = np.radians([light_deg, tilt_deg, rotation_deg])
    q = np.zeros(4)
    q[rig.axes.index("light_elevation")] = theta
    q[rig.axes.index("detector_elevation")] = 2.0 * alpha - theta  # the nominal peak is −θ
    q[rig.axes.index("sample_rotation")] = psi
    # The stage turned by ψ carries the tilt: toward the light (lab +x) at azimuth −ψ.
    wi, wo = rig.forward(q, Alignment(tilt=alpha, tilt_azimuth=-psi))
    mirror = wi * np.array([-1.0, -1.0, 1.0])
    assert angle_between(wo, mirror) < 1e-12
    nominal_i, nominal_o = rig.forward(q)
    assert abs(angle_between(nominal_o, nominal_i * [-1.0, -1.0, 1.0]) - 2 * abs(alpha)) < 1e-12


@pytest.mark.parametrize("name", ["arch", "in_plane"])
@given(seed=SEEDS, e=st.floats(-EPS, EPS))
@settings(max_examples=20, deadline=None)
def test_a_pointing_error_about_the_last_axis_is_its_zero_offset(
    name: str, seed: int, e: float
) -> None:
    """Both shipped types end their light and detector chains with an axis about y: a
    pointing error about y is that axis's zero offset (one parameter a fit cannot split)."""
    rig = RIGS[name]
    q = poses(rig, np.random.default_rng(seed))
    for chain in ("light", "detector"):
        last = rig.axes.index(getattr(rig.spec, chain).axes[-1])
        offset = np.zeros(len(rig.axes))
        offset[last] = e
        pointing = Alignment(**{f"{chain}_pointing": (0.0, e)})  # type: ignore[arg-type]
        for got, want in zip(
            rig.forward(q, pointing), rig.forward(q, Alignment(zero_offset=offset)), strict=True
        ):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


@given(NAMES, SEEDS)
@settings(max_examples=20, deadline=None)
def test_small_errors_move_the_directions_linearly(name: str, seed: int) -> None:
    """f(2εp) − f(0) = 2 (f(εp) − f(0)) + O(ε²): the map's first order is a Jacobian."""
    rig = RIGS[name]
    rng = np.random.default_rng(seed)
    q = poses(rig, rng)
    p = random_alignment(rig, rng, 1.0)
    eps = 1e-6

    def scaled(k: float) -> Alignment:
        return Alignment(
            zero_offset=k * p.zero_offset,
            tilt=k * p.tilt,
            tilt_azimuth=p.tilt_azimuth,
            height_mm=k * p.height_mm,
            light_pointing=k * p.light_pointing,
            detector_pointing=k * p.detector_pointing,
        )

    base = rig.forward(q)
    one, two = rig.forward(q, scaled(eps)), rig.forward(q, scaled(2 * eps))
    for b, a1, a2 in zip(base, one, two, strict=True):
        first = a1 - b
        assert np.max(np.abs(first)) > 1e-8  # something moved
        assert np.max(np.abs((a2 - b) - 2.0 * first)) < 1e3 * eps**2


@given(NAMES, SEEDS)
@settings(max_examples=15, deadline=None)
def test_a_batch_of_alignments_is_each_alone(name: str, seed: int) -> None:
    rig = RIGS[name]
    rng = np.random.default_rng(seed)
    q = poses(rig, rng, 8)
    each = [random_alignment(rig, rng, 0.05) for _ in range(3)]
    batch = Alignment(
        zero_offset=np.stack([a.zero_offset for a in each])[:, None, :],
        tilt=np.stack([a.tilt for a in each])[:, None],
        tilt_azimuth=np.stack([a.tilt_azimuth for a in each])[:, None],
        height_mm=np.stack([a.height_mm for a in each])[:, None],
        light_pointing=np.stack([a.light_pointing for a in each])[:, None, :],
        detector_pointing=np.stack([a.detector_pointing for a in each])[:, None, :],
    )
    assert batch.batch_shape == (3, 1)
    wi, wo = rig.forward(q, batch)
    assert wi.shape == wo.shape == (3, 8, 3)
    zeros = Alignment(tilt=np.zeros((3, 1)))
    assert zeros.is_none and rig.forward(q, zeros)[0].shape == (3, 8, 3)
    for k, alignment in enumerate(each):
        one = rig.forward(q, alignment)
        np.testing.assert_allclose(wi[k], one[0], rtol=0, atol=1e-15)
        np.testing.assert_allclose(wo[k], one[1], rtol=0, atol=1e-15)


@given(NAMES, SEEDS, st.sampled_from([-1.0, 1.0]))
@settings(max_examples=20, deadline=None)
def test_the_bounds_extremes_give_finite_unit_directions(name: str, seed: int, sign: float) -> None:
    rig = RIGS[name]
    spec = AlignmentSpec(
        zero_offset_deg=dict.fromkeys(rig.axes, sign * MAX_ERROR_DEG),
        tilt_deg=MAX_ERROR_DEG,
        tilt_azimuth_deg=sign * 360.0,
        height_mm=sign * MAX_HEIGHT_MM,
        light_pointing_deg=(sign * MAX_ERROR_DEG, -sign * MAX_ERROR_DEG),
        detector_pointing_deg=(-sign * MAX_ERROR_DEG, sign * MAX_ERROR_DEG),
    )
    g = rig.geometry(poses(rig, np.random.default_rng(seed)), spec.alignment(rig.axes))
    for value in (g.wi, g.wo, g.light_offset_mm, g.view_offset_mm):
        assert np.all(np.isfinite(value))
    np.testing.assert_allclose(np.linalg.norm(g.wi, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(g.wo, axis=-1), 1.0, atol=1e-14)


@given(st.floats(0.0, 75.0), st.floats(-MAX_HEIGHT_MM, MAX_HEIGHT_MM))
@settings(max_examples=40, deadline=None)
def test_a_height_shifts_spots_and_turns_only_a_point_sources_direction(
    light_deg: float, height: float
) -> None:
    """Collimated beam, distant detector: directions kept, spots shifted by h tan θ
    along their azimuth. Point source at r: s = r ωi − h z, its angle from the nominal
    h sin θ / r to first order."""
    theta = math.radians(light_deg)
    q = np.array([theta, 0.0, -theta, 0.0])
    alignment = Alignment(height_mm=height)
    beam = RIGS["arch"].geometry(q, alignment)
    nominal = RIGS["arch"].forward(q)
    assert np.array_equal(beam.wi, nominal[0]) and np.array_equal(beam.wo, nominal[1])
    np.testing.assert_allclose(beam.light_offset_mm, [height * math.tan(theta), 0.0], atol=1e-12)
    np.testing.assert_allclose(beam.view_offset_mm, [-height * math.tan(theta), 0.0], atol=1e-12)
    assert beam.light_distance_mm is None
    point = RIGS["arch_point"]
    r = point.spec.light.distance_mm
    assert r is not None
    lamp = point.geometry(q, alignment)
    assert lamp.light_distance_mm is not None
    s = r * nominal[0] - [0.0, 0.0, height]
    np.testing.assert_allclose(lamp.light_distance_mm, np.linalg.norm(s), rtol=1e-14)
    turned = float(angle_between(lamp.wi, nominal[0]))
    assert abs(turned - abs(height) * math.sin(theta) / r) <= (height / r) ** 2 + 1e-14
    assert np.array_equal(lamp.wo, nominal[1])


@given(st.floats(0.0, EPS), st.floats(-4.0, 4.0))
@settings(max_examples=30, deadline=None)
def test_the_tilt_rotation_takes_the_stage_axis_to_the_true_normal(
    tilt: float, azimuth: float
) -> None:
    alignment = Alignment(tilt=tilt, tilt_azimuth=azimuth)
    turned = alignment.tilt_rotation() @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(turned, alignment.normal, rtol=0, atol=1e-15)
    assert abs(float(np.arccos(np.clip(turned[2], -1.0, 1.0))) - tilt) < 1e-7


def test_an_offset_for_an_axis_the_rig_has_not_is_refused() -> None:
    spec = AlignmentSpec(zero_offset_deg={"nope": 0.1})
    with pytest.raises(ValueError, match="no axis 'nope'"):
        spec.alignment(RIGS["arch"].axes)
    assert spec.unknown_axes(RIGS["arch"].axes) == ["nope"]


def test_a_non_finite_or_misshapen_parameter_is_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        Alignment(tilt=math.nan)
    with pytest.raises(ValueError, match="two angles"):
        Alignment(light_pointing=(0.1, 0.2, 0.3))
