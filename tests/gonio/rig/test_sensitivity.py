"""Joint errors through the rig's kinematics into directions, coordinates and f."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio import brdf, params
from gonio.errors import DomainError
from gonio.params import conditioning
from gonio.rig import sensitivity
from gonio.rig.model import Rig

ARCH = Rig.from_yaml("configs/rigs/arch.yaml")
IN_PLANE = Rig.from_yaml("configs/rigs/in_plane.yaml")
TICK = 2.0 * math.pi / 4096
# arch: light_elevation, detector_azimuth (2:1 belt), detector_elevation, sample_rotation
Q = np.array([0.5, 0.3, 0.7, 0.2])
GGX = brdf.create("cook_torrance", alpha=0.1, f0=0.04)


def coordinates(name: str, rig: Rig, q: np.ndarray) -> np.ndarray:
    return params.get(name).forward(*rig.forward(q))


def test_axis_errors_are_one_tick_through_each_gear() -> None:
    e = sensitivity.axis_errors(ARCH, repeatability_rad=3e-4)
    np.testing.assert_allclose(e.tick, [TICK, TICK / 2, TICK, TICK], rtol=1e-15)
    np.testing.assert_allclose(e.quantization, e.tick / math.sqrt(12))
    np.testing.assert_allclose(e.total, np.hypot(e.tick / math.sqrt(12), 3e-4))
    tilt = IN_PLANE.axes.index("sample_tilt")
    assert sensitivity.axis_errors(IN_PLANE).tick[tilt] == pytest.approx(TICK / 3)


def test_spherical_standard_errors_by_hand_on_the_arch() -> None:
    # θi = light elevation, φi = −ψ, θo = detector elevation, φo = detector azimuth − ψ.
    q = sensitivity.axis_errors(ARCH).quantization
    got = sensitivity.coordinate_sigma("spherical", ARCH, Q, q)
    s = TICK / math.sqrt(12)
    np.testing.assert_allclose(got, [s, s, s, math.hypot(s / 2, s)], rtol=1e-8)


@pytest.mark.parametrize("name", params.names())
@pytest.mark.parametrize("rig", [ARCH, IN_PLANE], ids=["arch", "in_plane"])
def test_the_chained_jacobian_is_that_of_joint_angles_to_coordinates(name: str, rig: Rig) -> None:
    wi = np.array([np.sin(0.6) * np.cos(0.4), np.sin(0.6) * np.sin(0.4), np.cos(0.6)])
    wo = np.array([np.sin(0.9) * np.cos(2.6), np.sin(0.9) * np.sin(2.6), np.cos(0.9)])
    q = rig.solve(wi[None], wo[None]).angles[0]
    chained = conditioning.tangent_jacobian(name, *rig.forward(q)) @ (
        sensitivity.kinematic_jacobian(rig, q)
    )
    h = 1e-6
    for j in range(len(q)):
        step = np.zeros(len(q))
        step[j] = h
        diff = coordinates(name, rig, q + step) - coordinates(name, rig, q - step)
        diff[[1, 3]] = (diff[[1, 3]] + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(chained[:, j], diff / (2 * h), atol=1e-8)


def test_brdf_sigma_of_one_axis_is_the_derivative_of_f_along_that_joint() -> None:
    h = 1e-6
    for j in range(4):
        sigma = np.zeros(4)
        sigma[j] = 2e-4
        step = np.zeros(4)
        step[j] = h
        slope = (GGX.eval(*ARCH.forward(Q + step)) - GGX.eval(*ARCH.forward(Q - step))) / (2 * h)
        got = sensitivity.brdf_sigma(GGX, ARCH, Q, sigma)
        assert got == pytest.approx(abs(float(slope)) * 2e-4, rel=1e-6, abs=1e-12)


@pytest.mark.parametrize("name", params.names())
def test_the_brdf_error_does_not_depend_on_the_parametrization(name: str) -> None:
    # f read through the inverse at the coordinates: ∂f̃/∂c · J_c = ∂f/∂q (chain rule).
    p = params.get(name)
    c = coordinates(name, ARCH, Q)
    h = 1e-6
    grad_c = np.zeros(4)
    for k in range(4):
        step = np.zeros(4)
        step[k] = h
        grad_c[k] = (GGX.eval(*p.inverse(c + step)) - GGX.eval(*p.inverse(c - step))) / (2 * h)
    wi, wo = ARCH.forward(Q)
    jc = conditioning.tangent_jacobian(name, wi, wo) @ (sensitivity.kinematic_jacobian(ARCH, Q))
    direct = sensitivity.brdf_gradient(GGX, wi, wo) @ sensitivity.kinematic_jacobian(ARCH, Q)
    np.testing.assert_allclose(grad_c @ jc, direct, rtol=1e-5, atol=1e-8)


def test_a_constant_brdf_has_no_position_error() -> None:
    lambert = brdf.create("lambert", albedo=0.5)
    assert sensitivity.brdf_sigma(lambert, ARCH, Q, np.full(4, 1e-3)) == pytest.approx(0, abs=1e-9)


def test_brdf_gradient_refuses_the_horizon_and_rgb_models() -> None:
    on = np.array([1.0, 0.0, 0.0])
    with pytest.raises(DomainError, match="above the horizon"):
        sensitivity.brdf_gradient(GGX, on, np.array([0.0, 0.0, 1.0]))
    rgb = brdf.create("cook_torrance", alpha=0.1, f0=(0.9, 0.6, 0.3))
    with pytest.raises(DomainError, match="grey"):
        sensitivity.brdf_gradient(rgb, *ARCH.forward(Q))
