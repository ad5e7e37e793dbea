"""Each refusal reason triggered by a named pair, on each rig where it can happen, with
its boundary predicted from the rig file (just inside: OK, just outside: refused), and
the priority of the checks: the first failing one in the order THETA_MAX, BLIND_SPOT,
FOOTPRINT (a collimated light), VIEW_OFF_SAMPLE (a point source), AXIS_LIMIT, COLLISION
wins.

AXIS_LIMIT cannot happen on the arch (θ ≤ theta_max = 80° < 85° of the light arm, and
of the two detector solutions ±θo one always has its azimuth outside the 179…181° gap;
the sample rotation spans more than a turn): see test_coverage for the dense check.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.rig import constraints
from gonio.rig.model import Rig
from gonio.rig.solution import Reason
from gonio.types import FloatArray
from tests.conftest import RIG_FILES
from tests.gonio.rig.helpers import column, in_tilted_plane
from tests.support.rigs import direction

#: A small step (degrees) across a boundary: far above rounding, far below any feature.
STEP = 1e-6


def reason(rig: Rig, wi: FloatArray, wo: FloatArray, *, isotropic: bool = False) -> Reason:
    solution = rig.solve(wi[None], wo[None], isotropic=isotropic)
    mask, reasons = rig.reachable(wi[None], wo[None], isotropic=isotropic)
    assert reasons[0] == solution.reasons[0]
    assert mask[0] == (reasons[0] == Reason.OK)
    return Reason(int(solution.reasons[0]))


def test_reason_order_is_the_documented_priority() -> None:
    assert [r.name for r in sorted(Reason)] == [
        "OK",
        "THETA_MAX",
        "BLIND_SPOT",
        "FOOTPRINT",
        "VIEW_OFF_SAMPLE",
        "AXIS_LIMIT",
        "COLLISION",
    ]
    assert Reason.AXIS_LIMIT.label == "axis_limit"


# -- THETA_MAX ---------------------------------------------------------------------------
def test_theta_max_of_the_detector(rig: Rig) -> None:
    limit = rig.spec.constraints.theta_max_deg
    wi = direction(30.0, 0.0)
    assert reason(rig, wi, direction(limit - STEP, 180.0)) == Reason.OK
    assert reason(rig, wi, direction(limit + STEP, 180.0)) == Reason.THETA_MAX


def test_theta_max_of_the_light(rig: Rig) -> None:
    limit = rig.spec.constraints.theta_max_deg
    assert reason(rig, direction(limit + STEP, 0.0), direction(30.0, 180.0)) == Reason.THETA_MAX
    # Just inside, the light is refused anyway, for its footprint (see below).
    assert reason(rig, direction(limit - STEP, 0.0), direction(30.0, 180.0)) == Reason.FOOTPRINT


# -- BLIND_SPOT --------------------------------------------------------------------------
def test_blind_spot(rig: Rig) -> None:
    gap = rig.spec.constraints.min_separation_deg
    assert gap == 8.0
    wi = direction(30.0, 0.0)
    assert reason(rig, wi, direction(35.0, 0.0)) == Reason.BLIND_SPOT  # 5° apart
    assert reason(rig, wi, direction(30.0 + gap - STEP, 0.0)) == Reason.BLIND_SPOT
    assert reason(rig, wi, direction(30.0 + gap + STEP, 0.0)) == Reason.OK
    assert reason(rig, wi, wi) == Reason.BLIND_SPOT  # retro-reflection
    # Across the normal: 4° + 4° on either side.
    assert reason(rig, direction(4.0 - STEP, 90.0), direction(4.0, 270.0)) == Reason.BLIND_SPOT
    assert reason(rig, direction(4.0 + STEP, 90.0), direction(4.0, 270.0)) == Reason.OK


# -- FOOTPRINT ---------------------------------------------------------------------------
def grazing_limits(rig: Rig) -> tuple[float, float]:
    """(θ where the lit ellipse's length D / cos θi reaches the detector's field of view,
    θ where it reaches the sample's diameter), degrees."""
    c = rig.spec.constraints
    return (
        math.degrees(math.acos(c.beam_diameter_mm / c.detector_fov_mm)),
        math.degrees(math.acos(c.beam_diameter_mm / c.sample_diameter_mm)),
    )


def test_grazing_limits_of_the_shipped_rigs(rig: Rig) -> None:
    fov, sample = grazing_limits(rig)
    assert fov == pytest.approx(76.1135, abs=1e-4)  # acos(6 / 25)
    assert sample == pytest.approx(78.4630, abs=1e-4)  # acos(6 / 30)
    assert fov < sample < rig.spec.constraints.theta_max_deg


@pytest.mark.parametrize(
    "wo",
    [direction(0.0, 0.0), direction(60.0, 90.0)],
    ids=["detector-at-normal", "detector-across"],
)
def test_footprint_leaves_the_detector_view(rig: Rig, wo: FloatArray) -> None:
    """The detector sees a circle of diameter F (at the normal), or an ellipse whose
    short axis F lies along the light's azimuth (detector 90° around): the lit ellipse,
    D / cos θi long, leaves it at cos θi = D / F."""
    fov, _ = grazing_limits(rig)
    assert reason(rig, direction(fov - STEP, 0.0), wo) == Reason.OK
    assert reason(rig, direction(fov + STEP, 0.0), wo) == Reason.FOOTPRINT


def test_footprint_leaves_the_sample(rig: Rig) -> None:
    """With the detector's ellipse long along the light's azimuth (θo = 60°, mirror side:
    F / cos θo = 50 mm), the sample's diameter S binds first: at cos θi = D / S."""
    fov, sample = grazing_limits(rig)
    wo = direction(60.0, 180.0)
    assert reason(rig, direction(0.5 * (fov + sample), 0.0), wo) == Reason.OK
    assert reason(rig, direction(sample - STEP, 0.0), wo) == Reason.OK
    assert reason(rig, direction(sample + STEP, 0.0), wo) == Reason.FOOTPRINT


def test_a_grazing_detector_alone_keeps_the_footprint(rig: Rig) -> None:
    """The detector's ellipse only grows toward grazing: never a footprint refusal."""
    limit = rig.spec.constraints.theta_max_deg
    for phi in (0.0, 45.0, 90.0, 180.0):
        assert reason(rig, direction(10.0, 0.0), direction(limit - STEP, phi)) == Reason.OK


# -- COLLISION ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("wi", "wo", "expected"),
    [
        ((70.0, 0.0), (75.0, 15.0), Reason.COLLISION),  # the case
        ((70.0, 123.0), (75.0, 138.0), Reason.COLLISION),  # turned about the normal
        ((70.0, 0.0), (75.0, -15.0), Reason.COLLISION),  # detector on the other side
        ((60.0, 0.0), (75.0, 0.5), Reason.COLLISION),  # the −θo solution is in the gap
        ((70.0, 0.0), (75.0, 24.9), Reason.COLLISION),
        ((70.0, 0.0), (75.0, 25.1), Reason.OK),  # arch turned past the box
        ((70.0, 0.0), (54.9, 15.0), Reason.OK),  # detector above the box
        ((54.9, 0.0), (75.0, 15.0), Reason.OK),  # light above the box
        ((55.1, 0.0), (75.0, 15.0), Reason.COLLISION),
        ((70.0, 0.0), (75.0, 180.0), Reason.OK),  # opposite side
    ],
)
def test_arch_collision(
    rigs: dict[str, Rig], wi: tuple[float, float], wo: tuple[float, float], expected: Reason
) -> None:
    """The arch's keep-out boxes: light ≥ 55° and detector ≥ 55° within 25° of azimuth of
    each other (the second and third boxes are the same place with the arch turned by π
    and the elevation negative)."""
    assert reason(rigs["arch"], direction(*wi), direction(*wo)) == expected


def test_in_plane_collision(rigs: dict[str, Rig]) -> None:
    """Sample tilted by 45° (box: 40…60°) and the detector arm low at 75° (box: 70…95°)
    on the same side; the mirror image (x → −x) puts the arm on the other side."""
    rig = rigs["in_plane"]
    wi, wo = in_tilted_plane(-45.0, -20.0), in_tilted_plane(-45.0, 75.0)
    assert reason(rig, wi, wo) == Reason.COLLISION
    solution = rig.solve(wi[None], wo[None])
    tilt, arm = column(rig, "sample_tilt"), column(rig, "detector_arm")
    # Both solutions (each offered with the rotation stage at ψ − 2π, ψ, ψ + 2π).
    pairs = {tuple(np.round(np.degrees(c), 9)) for c in solution.candidates[0][:, [tilt, arm]]}
    assert pairs == {(45.0, 75.0), (-45.0, -75.0)}
    mirror = np.array([-1.0, 1.0, 1.0])
    assert reason(rig, wi * mirror, wo * mirror) == Reason.OK
    assert reason(rig, in_tilted_plane(-39.0, -20.0), in_tilted_plane(-39.0, 75.0)) == Reason.OK
    assert reason(rig, in_tilted_plane(-45.0, -20.0), in_tilted_plane(-45.0, 69.0)) == Reason.OK


# -- AXIS_LIMIT --------------------------------------------------------------------------
def test_in_plane_axis_limit_of_the_sample_tilt(rigs: dict[str, Rig]) -> None:
    """A pair whose plane is tilted more than the tilt stage's 59° from the vertical."""
    rig = rigs["in_plane"]
    limit = rig.spec.axes["sample_tilt"].max_deg
    for sign in (1.0, -1.0):
        inside = sign * (limit - STEP)
        outside = sign * (limit + STEP)
        assert reason(rig, in_tilted_plane(inside, -30.0), in_tilted_plane(inside, 30.0)) == (
            Reason.OK
        )
        assert reason(rig, in_tilted_plane(outside, -30.0), in_tilted_plane(outside, 30.0)) == (
            Reason.AXIS_LIMIT
        )
    assert reason(rig, in_tilted_plane(75.0, -10.0), in_tilted_plane(75.0, 40.0)) == (
        Reason.AXIS_LIMIT
    )


def test_arch_reaches_across_the_azimuth_gap(rigs: dict[str, Rig]) -> None:
    """Detector opposite the light: the +θo solution needs azimuth π, in the arch's gap
    (±179°); the −θo solution (azimuth 0) is used instead."""
    rig = rigs["arch"]
    wi, wo = direction(30.0, 0.0), direction(40.0, 180.0)
    assert reason(rig, wi, wo) == Reason.OK
    solution = rig.solve(wi[None], wo[None])
    assert solution.angles[0, column(rig, "detector_elevation")] == pytest.approx(
        -math.radians(40.0)
    )


# -- priority ----------------------------------------------------------------------------
def failing(rig: Rig, wi: FloatArray, wo: FloatArray) -> set[Reason]:
    """Every check the pair fails, each evaluated on its own."""
    c = rig.spec.constraints
    solution = rig.solve(wi[None], wo[None])
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    in_limits = np.all((solution.candidates >= lo) & (solution.candidates <= hi), axis=-1)
    out = set()
    if max(np.degrees(np.arccos([wi[2], wo[2]]))) > c.theta_max_deg:
        out.add(Reason.THETA_MAX)
    if np.degrees(constraints.separation(wi, wo)) < c.min_separation_deg:
        out.add(Reason.BLIND_SPOT)
    if c.beam_diameter_mm is not None and not constraints.footprint_ok(
        wi, wo, c.beam_diameter_mm, c.sample_diameter_mm, c.detector_fov_mm
    ):
        out.add(Reason.FOOTPRINT)
    if c.beam_diameter_mm is None and c.detector_fov_mm > c.sample_diameter_mm * wo[2]:
        out.add(Reason.VIEW_OFF_SAMPLE)
    if not in_limits.any():
        out.add(Reason.AXIS_LIMIT)
    if not solution.usable.any():
        out.add(Reason.COLLISION)
    return out


@pytest.mark.parametrize(
    ("name", "wi", "wo", "fails", "wins"),
    [
        (
            "arch",
            direction(85.0, 0.0),
            direction(87.0, 0.0),
            set(Reason) - {Reason.OK, Reason.VIEW_OFF_SAMPLE},  # 87°: past the 85° arm too
            Reason.THETA_MAX,
        ),
        (
            "in_plane",
            direction(85.0, 0.0),
            direction(87.0, 0.0),
            {Reason.THETA_MAX, Reason.BLIND_SPOT, Reason.FOOTPRINT},
            Reason.THETA_MAX,
        ),
        (
            "arch",
            direction(79.0, 0.0),
            direction(75.0, 0.0),
            {Reason.BLIND_SPOT, Reason.FOOTPRINT, Reason.COLLISION},
            Reason.BLIND_SPOT,
        ),
        (
            "arch",
            direction(79.0, 0.0),
            direction(60.0, 10.0),
            {Reason.FOOTPRINT, Reason.COLLISION},
            Reason.FOOTPRINT,
        ),
        (
            "in_plane",
            in_tilted_plane(75.0, -40.0),
            in_tilted_plane(75.0, 30.0),
            {Reason.FOOTPRINT, Reason.AXIS_LIMIT, Reason.COLLISION},
            Reason.FOOTPRINT,
        ),
    ],
    ids=[
        "theta_max-over-all-arch",
        "theta_max-over-blind_spot-in_plane",
        "blind_spot-over-footprint",
        "footprint-over-collision",
        "footprint-over-axis_limit",
    ],
)
def test_first_failing_check_wins(
    rigs: dict[str, Rig],
    name: str,
    wi: FloatArray,
    wo: FloatArray,
    fails: set[Reason],
    wins: Reason,
) -> None:
    rig = rigs[name]
    assert failing(rig, wi, wo) == fails
    assert reason(rig, wi, wo) == wins


def test_a_point_sources_view_leaves_the_sample(arch_point: Rig) -> None:
    """A lamp floods the sample: the detector's view (F / cos θo along its azimuth) must
    stay on it, so the detector is refused beyond cos θo = F / S, whatever the light."""
    c = arch_point.spec.constraints
    edge = math.degrees(math.acos(c.detector_fov_mm / c.sample_diameter_mm))
    for wi in (direction(0.0, 0.0), direction(70.0, 90.0)):
        assert reason(arch_point, wi, direction(edge - STEP, 180.0)) == Reason.OK
        assert reason(arch_point, wi, direction(edge + STEP, 180.0)) == Reason.VIEW_OFF_SAMPLE


def test_the_view_refusal_in_its_place(arch_point: Rig) -> None:
    """After the blind spot, before the collisions (light and detector both ≥ 55° within
    25° of azimuth hit the low light arm)."""
    wi, wo = direction(60.0, 0.0), direction(63.0, 0.0)
    assert failing(arch_point, wi, wo) == {
        Reason.BLIND_SPOT,
        Reason.VIEW_OFF_SAMPLE,
        Reason.COLLISION,
    }
    assert reason(arch_point, wi, wo) == Reason.BLIND_SPOT
    wi, wo = direction(60.0, 0.0), direction(70.0, 10.0)
    assert failing(arch_point, wi, wo) == {Reason.VIEW_OFF_SAMPLE, Reason.COLLISION}
    assert reason(arch_point, wi, wo) == Reason.VIEW_OFF_SAMPLE


def test_axis_limit_over_collision(tmp_path: Path) -> None:
    """The in-plane tilt box reaches 60°, past the stage's 59°: a pose there is out of the
    limits and in the box. The shipped rig's θmax hides such pairs (θo ≥ 79.9°), so the
    test raises θmax to 89°."""
    data = yaml.safe_load(RIG_FILES["in_plane"].read_text())
    data["constraints"]["theta_max_deg"] = 89
    path = tmp_path / "steep.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    rig = Rig.from_yaml(path)
    wi, wo = in_tilted_plane(-59.5, -20.0), in_tilted_plane(-59.5, 75.0)
    assert failing(rig, wi, wo) == {Reason.AXIS_LIMIT, Reason.COLLISION}
    assert reason(rig, wi, wo) == Reason.AXIS_LIMIT
    wi, wo = in_tilted_plane(-58.0, -20.0), in_tilted_plane(-58.0, 75.0)
    assert failing(rig, wi, wo) == {Reason.COLLISION}
    assert reason(rig, wi, wo) == Reason.COLLISION
