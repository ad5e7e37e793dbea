"""The scaled space: every seam copy is a copy of its sample, and each pole's mirror
rule continues a path of pairs through the pole."""

from __future__ import annotations

import numpy as np
import pytest

from gonio import params
from gonio.reconstruct.coordinates import JITTER, Space, morton_order

SPACES = [(name, iso) for name in params.names() for iso in (True, False)]


def _unit(theta: float, phi: float) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _rot_y(t: np.ndarray, w: np.ndarray) -> np.ndarray:
    """w rotated about y by each angle t: (len(t), 3)."""
    c, s = np.cos(t), np.sin(t)
    return np.stack([c * w[0] + s * w[2], np.full(len(t), w[1]), c * w[2] - s * w[0]], axis=1)


@pytest.mark.parametrize(("name", "isotropic"), SPACES)
def test_every_copy_is_its_sample_seen_across_a_seam(name: str, isotropic: bool) -> None:
    space = Space(name, isotropic)
    rng = np.random.default_rng(0)
    p = params.get(name)
    wi, wo = (p.inverse_iso if isotropic else p.inverse)(_valid(p, isotropic, rng))
    x = space.scaled(wi, wo)
    padded = space.pad(x, 0.1)
    copies = padded.points[len(x) :]
    assert len(copies) > len(x) // 10
    home = space.canonical(copies)
    source = x[padded.source[len(x) :]]
    if space.reciprocal_copies:
        swapped = space.reciprocal(source)
        near = np.minimum(_gap(home, source, space), _gap(home, swapped, space))
    else:
        near = _gap(home, source, space)
    assert near.max() < 10 * JITTER


def _valid(p: params.Parametrization, isotropic: bool, rng: np.random.Generator) -> np.ndarray:
    bounds = p.iso_bounds if isotropic else p.bounds
    c = bounds[:, 1] * rng.random((6000, len(bounds)))
    return c[(p.valid_iso if isotropic else p.valid)(c)][:2000]


def _gap(a: np.ndarray, b: np.ndarray, space: Space) -> np.ndarray:
    d = np.abs(a - b)
    for axis, period in space.periods:
        d[:, axis] = np.minimum(d[:, axis], period - d[:, axis])
    return d.max(axis=1)


def _pole_paths(name: str, isotropic: bool) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Pair paths (wi, wo) over t ∈ [−δ, δ] whose given radial coordinate crosses 0."""
    t = np.linspace(-0.02, 0.02, 41) + 1e-4  # never exactly at the pole
    w = _unit(0.7, 0.4)
    fixed = np.tile(_unit(0.5, 2.5), (len(t), 1))
    mirror = (_unit(0.6, 0.3), _unit(0.6, 0.3 + np.pi))
    tilted = (_rot_y(t, mirror[0]), _rot_y(t, mirror[1]))
    apart = (_rot_y(t, w), _rot_y(-t, w))
    crossing = (_rot_y(t, _unit(0.0, 0.0)), fixed)
    if name == "spherical":
        second = (fixed, crossing[0])
        return {0: crossing, (1 if isotropic else 2): second}
    return {0: tilted, (1 if isotropic else 2): apart}


@pytest.mark.parametrize(("name", "isotropic"), SPACES)
def test_the_pole_rules_continue_a_path_through_each_pole(name: str, isotropic: bool) -> None:
    space = Space(name, isotropic)
    paths = _pole_paths(name, isotropic)
    for radial, shifts in space.poles:
        wi, wo = paths[radial]
        x = space.scaled(wi, wo)
        before = np.arange(len(x)) < np.argmin(x[:, radial])  # the side t < 0
        x[before, radial] *= -1.0
        for axis, shift in shifts:
            x[before, axis] -= shift
        step = np.abs(np.diff(x, axis=0))
        for axis, period in space.periods:
            step[:, axis] = np.minimum(step[:, axis] % period, period - step[:, axis] % period)
        # An azimuth undefined at the pole turns fast near it, but never jumps by the
        # half turn a wrong rule leaves; radii move by the path's step.
        assert step[:, radial].max() < 5e-3, (name, isotropic, radial)
        for axis, _ in space.periods:
            assert step[:, axis].max() < 0.2, (name, isotropic, radial, axis)


def test_the_z_order_keeps_neighbours_close() -> None:
    x = np.random.default_rng(1).random((4000, 3))

    def median_step(y: np.ndarray) -> float:
        return float(np.median(np.linalg.norm(np.diff(y, axis=0), axis=1)))

    assert median_step(x[morton_order(x)]) < 0.2 * median_step(x)
