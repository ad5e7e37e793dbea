"""Line data: lines found from coordinates or given, the ``lines`` interpolant exact at
its samples and reproducing what is linear along lines and affine across them, ``rbf``
stable on line data, both far better than ``linear`` there, and ``lines`` refused in one
line on data without lines."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.analysis.measured import Measured
from gonio.brdf.base import BRDF
from gonio.errors import GonioError
from gonio.reconstruct import evaluate, reconstruct, testset
from gonio.reconstruct.coordinates import Space
from gonio.reconstruct.lines import Lines, line_labels, line_set
from gonio.rig.model import Rig
from gonio.types import FloatArray
from studies.reconstruct.synthetic_lines import synthesize_lines

SPACE = Space("rusinkiewicz", isotropic=True)


@pytest.fixture(scope="module")
def layout() -> tuple[FloatArray, np.ndarray]:
    """Scaled samples of 40 lines every 1° (θh from 0 to 80°), and their lines."""
    rng = np.random.default_rng(5)  # no two lines within 0.029 of each other
    position = rng.uniform([0.05, 0.0], [0.95, 1.0], size=(40, 2))
    t = np.radians(np.arange(0.0, 81.0)) / (np.pi / 2)
    x = np.column_stack([np.tile(t, 40), np.repeat(position, len(t), axis=0)])
    return x, np.repeat(np.arange(40), len(t))


def test_lines_are_found_from_coordinates_up_to_a_jitter(
    layout: tuple[FloatArray, np.ndarray],
) -> None:
    x, label = layout
    jittered = x + np.column_stack(
        [np.zeros(len(x)), 2e-4 * np.random.default_rng(0).standard_normal((len(x), 2))]
    )
    scattered = np.random.default_rng(1).uniform(size=(30, 3))
    found = line_labels(np.concatenate([jittered, scattered]))
    np.testing.assert_array_equal(found[: len(x)], label)  # numbered by first sample
    assert (found[len(x) :] == -1).all()
    lines = line_set(x, label)
    assert len(lines) == 40 and lines.share == 1.0 and lines.structured
    np.testing.assert_allclose(lines.positions, x[:: len(x) // 40, 1:])


def test_given_labels_name_lines_and_short_ones_are_none(
    layout: tuple[FloatArray, np.ndarray],
) -> None:
    x, label = layout
    given_ = np.where(label == 7, -5, label * 3)
    given_[:2] = 1000  # a line of two samples: none
    lines = line_set(x, given_)
    assert len(lines) == 39 and (lines.labels[label == 7] == -1).all()
    assert (lines.labels[:2] == -1).all()
    with pytest.raises(GonioError, match="one integer per sample"):
        line_set(x, label.astype(float))


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.floats(-2.0, 2.0), min_size=4, max_size=4),
    st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
)
def test_lines_reproduce_what_is_linear_along_and_affine_across(
    layout: tuple[FloatArray, np.ndarray], across: list[float], along: list[float]
) -> None:
    """g = a0 + a1 t + a2 θd + a3 φd (+ b t·(θd, φd) in a second column: bilinear)."""
    x, label = layout
    a, b = np.array(across), np.array(along)

    def g(p: FloatArray) -> FloatArray:
        affine = a[0] + p @ a[1:]
        bilinear = b[0] + p[:, 0] * (b[1] * p[:, 1] + b[2] * p[:, 2])
        return np.column_stack([affine, bilinear])

    interpolant = Lines(x, g(x), line_set(x, label), SPACE)
    rng = np.random.default_rng(5)
    # Away from the seams, whose copies of a line are not affine copies.
    queries = np.column_stack([rng.uniform(0, 0.85, 400), rng.uniform(0.4, 0.6, (400, 2))])
    got, defined = interpolant(queries, np.zeros(400, dtype=np.intp))
    assert defined.all()
    np.testing.assert_allclose(got[:, 0], g(queries)[:, 0], atol=1e-9)
    np.testing.assert_allclose(got[:, 1], g(queries)[:, 1], atol=1e-9)
    at_samples, ok = interpolant(x, np.zeros(len(x), dtype=np.intp))
    assert ok.all()
    np.testing.assert_allclose(at_samples, g(x), atol=1e-9)


def test_outside_the_lines_nothing_is_defined(layout: tuple[FloatArray, np.ndarray]) -> None:
    x, label = layout
    interpolant = Lines(x, x[:, :1], line_set(x, label), SPACE)
    beyond = np.array([[0.95, 0.5, 0.5], [0.3, 0.99, 0.5]])  # past 80°; past every θd
    got, defined = interpolant(beyond, np.zeros(2, dtype=np.intp))
    assert not defined.any() and np.isnan(got).all()


@pytest.fixture(scope="module")
def glossy_lines(arch: Rig) -> tuple[Measured, np.ndarray, BRDF]:
    from gonio import brdf

    gold = brdf.create(
        "cook_torrance",
        alpha=0.05,
        fresnel="conductor",
        ior=[0.18, 0.42, 1.37],
        k=[3.42, 2.35, 1.77],
    )
    measured, label = synthesize_lines(lambda wi, wo: gold.eval(wi, wo).mean(-1), arch, 64, 0.5)
    return measured, label, gold


def test_line_data_are_reconstructed_by_lines_and_rbf_far_better_than_linear(
    arch: Rig, glossy_lines: tuple[Measured, np.ndarray, BRDF]
) -> None:
    measured, label, gold = glossy_lines
    pairs = testset.draw(arch, isotropic=True, size=3000)
    truth = lambda wi, wo: gold.eval(wi, wo).mean(-1)  # noqa: E731
    score = {}
    for method in ("lines", "rbf"):
        r = reconstruct(measured, method=method, extrapolate="nearest")
        result = evaluate(r, truth, arch, isotropic=True, test_set=pairs).regions["all"]
        assert result.coverage is not None and result.coverage > 0.95
        score[method] = result.scores.log_rmse
    # the labels of the plan's sweeps give the lines the coordinates give
    given_ = reconstruct(measured, method="lines", lines=label, extrapolate="nearest")
    assert evaluate(given_, truth, arch, isotropic=True, test_set=pairs).regions[
        "all"
    ].scores.log_rmse == pytest.approx(score["lines"], rel=1e-12)
    assert score["lines"] < 0.02 and score["rbf"] < 0.02, score
    assert all(np.isfinite(reconstruct(measured, method="rbf").eval(pairs.wi, pairs.wo)))


def test_lines_are_refused_in_one_line_without_lines(matte_iso: Measured) -> None:
    with pytest.raises(GonioError, match="method 'lines' needs samples on lines") as err:
        reconstruct(matte_iso, method="lines")
    assert "\n" not in str(err.value)
    with pytest.raises(GonioError, match="not lines of isotropic 'spherical'"):
        reconstruct(
            matte_iso,
            method="lines",
            parametrization="spherical",
            lines=np.arange(len(matte_iso)) // 50,
        )


def test_rbf_on_too_few_lines_is_one_line(
    arch: Rig, glossy_lines: tuple[Measured, np.ndarray, BRDF]
) -> None:
    """Two lines are not line data (fewer than four): the solve is singular or so
    ill-conditioned that its values overflow; a refusal, not a warning or inf."""
    measured, label, _ = glossy_lines
    pairs = testset.draw(arch, isotropic=True, size=500)
    for lines in (1, 2, 3):
        r = reconstruct(measured.subset(label < lines), method="rbf", max_distance=1.0)
        with pytest.raises(GonioError, match="method 'rbf': the samples nearest") as err:
            r.eval(pairs.wi, pairs.wo)
        assert "\n" not in str(err.value)
