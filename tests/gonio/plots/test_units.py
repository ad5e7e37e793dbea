"""Every figure of `gonio plot` and `gonio plan --plot` draws angles in degrees and says so:
the coordinates that are angles are drawn in degrees on axes labelled (°), captions give
an angle's value with its unit, and no text speaks of radians. Read from the figures
matplotlib drew, as saved."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gonio import params
from gonio.planner import build
from gonio.planner.schema import PlanSpec
from gonio.plots import ANGLES, LABELS, coverage, drawn, error, polar, quantity, samples, slices
from gonio.reconstruct import testset
from gonio.rig.model import Rig
from tests.support.figures import Lobe, assert_angles_in_degrees, capture, texts


@pytest.fixture(scope="module")
def pairs(rigs: dict[str, Rig]) -> testset.TestSet:
    return testset.draw(rigs["arch"], isotropic=False, size=300, seed=2)


def test_the_coordinates_named_for_angles_are_the_angles() -> None:
    for name in params.names():
        p = params.get(name)
        for coordinate in (*p.names, *p.iso_names):
            angle = coordinate.startswith(("theta", "phi"))
            assert (coordinate in ANGLES) == angle, coordinate
            assert LABELS[coordinate].endswith(" (°)") == angle, LABELS[coordinate]
    np.testing.assert_array_equal(drawn("phi_d", [0.0, math.pi / 8]), [0.0, 22.5])
    np.testing.assert_array_equal(drawn("hbar", [0.0, 0.5]), [0.0, 0.5])
    assert quantity("phi_d", math.pi / 8) == "22.5°"
    assert quantity("k", 0.125) == "0.125"


@pytest.mark.parametrize("parametrization", ["rusinkiewicz", "hybrid"])
def test_the_coverage_of_a_plan(
    parametrization: str, rigs: dict[str, Rig], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    spec = PlanSpec.model_validate(
        {
            "name": "units",
            "parametrization": parametrization,
            "sampling": {"strategy": "sobol", "target": 60},
            "kicks": 5,
        }
    )
    plan = build(spec, rigs["arch"])
    monkeypatch.setattr(coverage, "RESOLUTION", 40)  # the shading is not what is checked
    figures = capture(monkeypatch, coverage)
    coverage.plot_coverage(plan, tmp_path / "coverage.png")
    (fig,) = figures
    assert_angles_in_degrees(fig)
    shown = texts(fig)
    if parametrization == "rusinkiewicz":  # φd over [0°, 180°] in four slabs
        assert "φd = 22.5° ± 22.5°\n" in "\n".join(shown)
        axes = fig.axes[0]  # type: ignore[attr-defined]
        assert (axes.get_xlabel(), axes.get_ylabel()) == ("θh (°)", "θd (°)")
        assert axes.get_xlim() == pytest.approx((0.0, 90.0))
    else:
        assert "φk − φh = 22.5° ± 22.5°\n" in "\n".join(shown)
        assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == ("‖h̄‖", "‖k‖")  # type: ignore[attr-defined]
    assert "θ limit of the rig: 80.0° (dashed)" in "\n".join(shown)


@pytest.mark.parametrize(
    ("parametrization", "isotropic"), [("rusinkiewicz", False), ("hybrid", True)]
)
def test_the_samples(
    parametrization: str,
    isotropic: bool,
    pairs: testset.TestSet,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    f = Lobe().eval(pairs.wi, pairs.wo)
    data = samples.coverage(
        (pairs.wi, pairs.wo, f, 0.1 * f),
        parametrization,
        isotropic=isotropic,
        theta_max=math.radians(80.0),
    )
    figures = capture(monkeypatch, samples)
    samples.draw(data, tmp_path / "samples.png")
    (fig,) = figures
    assert_angles_in_degrees(fig)
    for (a, b), ax in zip(samples.PROJECTIONS[len(data.names)], fig.axes[3:6], strict=True):  # type: ignore[attr-defined]
        (dots,) = ax.collections
        expected = np.stack(
            [drawn(data.names[a], data.coords[:, a]), drawn(data.names[b], data.coords[:, b])],
            axis=-1,
        )
        np.testing.assert_array_equal(dots.get_offsets(), expected)


@pytest.mark.parametrize("parametrization", ["rusinkiewicz", "hybrid"])
def test_the_error_maps(
    parametrization: str, pairs: testset.TestSet, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    data = error.errors(Lobe(), lambda wi, wo: 1.2 * Lobe().eval(wi, wo), pairs, parametrization)
    figures = capture(monkeypatch, error)
    error.draw(data, tmp_path / "error.png")
    (fig,) = figures
    assert_angles_in_degrees(fig)
    if parametrization == "rusinkiewicz":
        ax = fig.axes[1]  # type: ignore[attr-defined]
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("θh (°)", "φd (°)")
        assert ax.get_ylim() == pytest.approx((0.0, 180.0))


def test_the_slices(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    data = slices.slices(Lobe(), (0.0, 45.0), resolution=15, title="a lobe")
    figures = capture(monkeypatch, slices)
    slices.draw(data, tmp_path / "slices.png")
    (fig,) = figures
    assert_angles_in_degrees(fig)
    shown = texts(fig)
    assert "rusinkiewicz, φd = 45°" in shown and "hybrid, φk − φh = 0°" in shown
    rusinkiewicz = fig.axes[4]  # type: ignore[attr-defined]
    assert rusinkiewicz.get_xlabel() == "θh (°)"
    assert rusinkiewicz.get_xlim()[1] == pytest.approx(90.0, abs=5.0)  # half a pixel beyond


def test_the_in_plane_curves(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    lobe = Lobe()
    wi, wo = polar.in_plane(math.radians(30.0), np.radians([-40.0, 0.0, 30.0]))
    f = lobe.eval(wi, wo)
    data = polar.polar(lobe, (wi, wo, f, 0.1 * f), math.radians(80.0), (30.0,))
    figures = capture(monkeypatch, polar)
    polar.draw(data, tmp_path / "polar.png")
    (fig,) = figures
    assert_angles_in_degrees(fig)
    ax: Any = fig.axes[0]  # type: ignore[attr-defined]
    assert ax.get_xlabel().startswith("θo (degrees;")
    assert ax.get_xlim()[1] > 60.0
