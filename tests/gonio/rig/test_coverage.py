"""Both shipped rigs reach the whole domain their files claim, on a dense random sample.

What a rig claims, from its file:

* geometry (properties of the pair alone, unchanged by turning it about the normal):
  θi, θo ≤ theta_max; separation ≥ min_separation; the lit ellipse inside the sample
  and inside the detector's view (footprint, a collimated light); the detector's view
  on the sample (a point source, which floods it: the view's chord along ωo's azimuth,
  F / cos θo, at most the sample's diameter);
* hardware: the axes' limits and the keep-out boxes (joint space).

The arch's limits never bind inside θ ≤ theta_max (80° < 85°; one of the two detector
solutions ±θo avoids the azimuth gap at ±180°; the rotation stage spans more than a
turn), and its boxes are, in direction space, light and detector both ≥ 55° within 25°
of azimuth of each other. The in-plane rig turns the pair's plane upright with the
sample tilt: its limits bind where the plane's normal rises more than 59° (the tilt
stage's range) above the horizon (the arms never bind: a direction above the sample's
horizon is within 90° of its normal); its boxes are tilt ≥ 40° with the detector arm
≥ 70° on the same side. The expected reason of every pair is computed from these
descriptions, independently of `gonio.rig` (the footprint by an eigenvalue solve).
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from gonio.types import FloatArray
from tests.conftest import RIG_NAMES
from tests.gonio.rig.helpers import TOL, column, wrap
from tests.support.rigs import uniform_directions

N = 100_000


def lit_inside_view(wi: FloatArray, wo: FloatArray, beam: float, fov: float) -> FloatArray:
    """True where the beam's ellipse fits in the detector's (containment of centred
    ellipses: the largest eigenvalue of Q_view⁻¹ Q_lit at most 1)."""

    def shape(w: FloatArray, diameter: float) -> FloatArray:
        phi = np.arctan2(w[:, 1], w[:, 0])
        u = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        v = np.stack([-u[:, 1], u[:, 0]], axis=-1)
        a, b = 0.5 * diameter / w[:, 2], 0.5 * diameter
        return np.asarray(
            (a**2)[:, None, None] * u[:, :, None] * u[:, None, :]
            + b**2 * v[:, :, None] * v[:, None, :],
            dtype=np.float64,
        )

    ratio = np.linalg.solve(shape(wo, fov), shape(wi, beam))
    return np.asarray(np.linalg.eigvals(ratio).real.max(axis=-1) <= 1.0, dtype=np.bool_)


def expected_reasons(rig: Rig, wi: FloatArray, wo: FloatArray) -> np.ndarray:
    c = rig.spec.constraints
    theta_i, theta_o = np.degrees(np.arccos(wi[:, 2])), np.degrees(np.arccos(wo[:, 2]))
    apart = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", wi, wo), -1.0, 1.0)))
    if c.beam_diameter_mm is None:  # a point source: no lit ellipse, the view on the sample
        footprint = np.ones(len(wi), dtype=bool)
        on_sample = theta_o <= np.degrees(np.arccos(c.detector_fov_mm / c.sample_diameter_mm))
    else:
        footprint = (c.beam_diameter_mm / wi[:, 2] <= c.sample_diameter_mm) & lit_inside_view(
            wi, wo, c.beam_diameter_mm, c.detector_fov_mm
        )
        on_sample = np.ones(len(wi), dtype=bool)
    if rig.spec.type == "arch":
        azimuths = np.degrees(
            np.arctan2(
                wi[:, 0] * wo[:, 1] - wi[:, 1] * wo[:, 0], wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]
            )
        )
        axis_limit = np.zeros(len(wi), dtype=bool)
        collision = (theta_i >= 55.0) & (theta_o >= 55.0) & (np.abs(azimuths) <= 25.0)
    else:
        m = np.cross(wi, wo)
        m /= np.linalg.norm(m, axis=1)[:, None]
        tilt = np.degrees(np.arcsin(np.abs(m[:, 2])))
        # The detector arm's angle in the upright plane: cos θo = cos(arm) cos(tilt); it is
        # on the tilt's side where m_z (m × ωo)_z > 0.
        arm = np.degrees(np.arccos(np.clip(wo[:, 2] / np.sqrt(1.0 - m[:, 2] ** 2), -1.0, 1.0)))
        same_side = m[:, 2] * np.cross(m, wo)[:, 2] > 0.0
        axis_limit = tilt > 59.0
        collision = (tilt >= 40.0) & (arm >= 70.0) & same_side
    checks = [
        (Reason.THETA_MAX, np.maximum(theta_i, theta_o) > c.theta_max_deg),
        (Reason.BLIND_SPOT, apart < c.min_separation_deg),
        (Reason.FOOTPRINT, ~footprint),
        (Reason.VIEW_OFF_SAMPLE, ~on_sample),
        (Reason.AXIS_LIMIT, axis_limit),
        (Reason.COLLISION, collision),
    ]
    out = np.full(len(wi), Reason.OK, dtype=np.int8)
    for reason, refused in reversed(checks):
        out[refused] = reason
    return out


def sample(seed: int, n: int = N) -> tuple[FloatArray, FloatArray]:
    """Pairs uniform in solid angle over θ ≤ 85° (a little past theta_max)."""
    rng = np.random.default_rng(seed)
    cap = np.radians(85.0)
    return uniform_directions(rng, n, cap), uniform_directions(rng, n, cap)


def test_the_point_source_rig_refuses_a_view_off_the_sample(arch_point: Rig) -> None:
    """The arch with a lamp (25 mm view, 30 mm sample): every pair whose view runs past
    the sample's edge (θo > 33.6°) is refused for it, and no pair for its footprint."""
    wi, wo = sample(12)
    _, reasons = arch_point.reachable(wi, wo)
    expected = expected_reasons(arch_point, wi, wo)
    wrong = reasons != expected
    assert not wrong.any(), Counter(
        zip(expected[wrong].tolist(), reasons[wrong].tolist(), strict=True)
    )
    counts = Counter(Reason(int(r)) for r in reasons)
    assert counts[Reason.VIEW_OFF_SAMPLE] > 10_000 and counts[Reason.OK] > 1000
    assert counts[Reason.FOOTPRINT] == 0


@pytest.mark.parametrize("name", RIG_NAMES)
def test_reaches_the_claimed_domain(rigs: dict[str, Rig], name: str) -> None:
    rig = rigs[name]
    wi, wo = sample(11)
    _, reasons = rig.reachable(wi, wo)
    for isotropic in (False, True):  # reachable skips choosing a pose: same reasons
        got = rig.reachable(wi, wo, isotropic=isotropic)[1]
        assert np.array_equal(got, rig.solve(wi, wo, isotropic=isotropic).reasons)
    expected = expected_reasons(rig, wi, wo)
    wrong = reasons != expected
    assert not wrong.any(), Counter(
        zip(expected[wrong].tolist(), reasons[wrong].tolist(), strict=True)
    )
    counts = Counter(Reason(int(r)) for r in reasons)
    # Every reason possible on the rig happens in the sample (so the test can fail).
    for r in (Reason.OK, Reason.THETA_MAX, Reason.BLIND_SPOT, Reason.FOOTPRINT):
        assert counts[r] > 100
    assert counts[Reason.COLLISION] > 100
    if name == "arch":
        assert counts[Reason.AXIS_LIMIT] == 0
    else:
        assert counts[Reason.AXIS_LIMIT] > 1000


@pytest.mark.parametrize("name", RIG_NAMES)
def test_geometry_alone_decides_up_to_the_hardware(rigs: dict[str, Rig], name: str) -> None:
    """Hardware refusals only where the description above puts them: every pair that
    passes the geometric checks and lies outside the keep-out and tilt regions is
    reached, and the arch is never short of axis range."""
    rig = rigs[name]
    wi, wo = sample(12)
    ok, reasons = rig.reachable(wi, wo)
    expected = expected_reasons(rig, wi, wo)
    assert np.array_equal(ok, expected == Reason.OK)
    if name == "arch":
        assert not np.any(reasons == Reason.AXIS_LIMIT)


@pytest.mark.parametrize("name", RIG_NAMES)
def test_isotropic_mode(rigs: dict[str, Rig], name: str) -> None:
    """isotropic=True keeps the sample rotation home and measures the pair turned about
    the normal: same θi, θo and azimuth difference (signed) as asked, FK of the angles
    is the measured pair, and the domain is the same as without the option (on these
    rigs the rotation stage never limits)."""
    rig = rigs[name]
    wi, wo = sample(13, 30_000)
    anisotropic = rig.solve(wi, wo)
    solution = rig.solve(wi, wo, isotropic=True)
    assert np.array_equal(solution.reasons, anisotropic.reasons)
    ok = solution.ok
    assert ok.mean() > 0.5
    angles, mi, mo = solution.angles[ok], solution.wi[ok], solution.wo[ok]
    ri, ro = wi[ok], wo[ok]
    rotation = column(rig, "sample_rotation")
    assert np.all(angles[:, rotation] == rig.home[rotation])
    fi, fo = rig.forward(angles)
    assert np.abs(fi - mi).max() <= TOL
    assert np.abs(fo - mo).max() <= TOL
    # The isotropic coordinates: cos θi, cos θo, and cos / sin of φo − φi (times sin θi
    # sin θo): the pair turned about the normal, not otherwise changed.
    assert np.abs(mi[:, 2] - ri[:, 2]).max() <= 1e-12
    assert np.abs(mo[:, 2] - ro[:, 2]).max() <= 1e-12
    assert np.abs(np.einsum("ij,ij->i", mi, mo) - np.einsum("ij,ij->i", ri, ro)).max() <= 1e-12
    cross_z = mi[:, 0] * mo[:, 1] - mi[:, 1] * mo[:, 0]
    assert np.abs(cross_z - (ri[:, 0] * ro[:, 1] - ri[:, 1] * ro[:, 0])).max() <= 1e-12
    assert np.abs(np.linalg.norm(mi, axis=1) - 1.0).max() <= 1e-12
    # It did turn them (so the checks above are not vacuous) ...
    assert np.median(np.linalg.norm(mi - ri, axis=1)) > 0.1
    # ... into a pose the rig reaches with the stage home.
    if name == "arch":
        assert np.abs(mi[:, 1]).max() <= 1e-12  # the light arm's plane: φi' ∈ {0, π}
    else:
        m = np.cross(mi, mo)
        assert np.abs(m[:, 0]).max() <= 1e-12  # the plane's normal turned to the y-z plane
    # The measured pair, solved without the option, is reachable and has the isotropic
    # pose among its candidates (not always as its pick: ties in travel time).
    again = rig.solve(mi, mo)
    assert again.ok.all()
    diff = again.candidates - angles[:, None, :]
    diff[..., rotation] = wrap(diff[..., rotation])
    assert np.abs(diff).max(axis=-1).min(axis=-1).max() <= TOL
