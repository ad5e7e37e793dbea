"""Truth SPECs: the scene, a model, a material or scene file, another run; and the one
line a SPEC that names nothing usable gets."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gonio import brdf
from gonio.analysis.measured import Measured
from gonio.errors import GonioError
from gonio.radiometry.bands import LUMINANCE
from gonio.reconstruct import testset
from gonio.reconstruct.naive import NaiveReconstruction
from gonio.reconstruct.truth import truth_from_spec
from tests.support.runs import SCENES, plan_spec, scene_spec, simulated_run

GLOSSY = "cook_torrance:alpha=0.05,fresnel=conductor,ior=[0.18, 0.42, 1.37],k=[3.42,2.35,1.77]"


@pytest.fixture(scope="module")
def run(runs_dir: Path) -> Path:
    return simulated_run(runs_dir, plan_spec(200), scene_spec("matte", noise=False))


@pytest.fixture(scope="module")
def measured(run: Path) -> Measured:
    return Measured.from_run(run)


@pytest.fixture(scope="module")
def pairs(measured: Measured) -> testset.TestSet:
    return testset.draw(measured.rig, isotropic=True, size=500)


@pytest.mark.parametrize("spec", [None, "scene"])
def test_the_default_is_the_scene(
    spec: str | None, measured: Measured, pairs: testset.TestSet
) -> None:
    truth = truth_from_spec(spec, measured)
    assert truth.label == f"the scene of {measured.source}" and truth.supported is None
    np.testing.assert_array_equal(
        truth.eval(pairs.wi, pairs.wo), measured.scene_truth()(pairs.wi, pairs.wo)
    )


def test_a_run_on_hardware_has_no_default_truth(measured: Measured) -> None:
    with pytest.raises(GonioError, match="a run on hardware has no scene to compare with"):
        truth_from_spec(None, replace(measured, scene_text=None))


def test_a_model_with_rgb_values_is_seen_through_the_band(
    measured: Measured, pairs: testset.TestSet
) -> None:
    model = brdf.create(
        "cook_torrance",
        alpha=0.05,
        fresnel="conductor",
        ior=[0.18, 0.42, 1.37],
        k=[3.42, 2.35, 1.77],
    )
    rgb = model.eval(pairs.wi, pairs.wo)
    luminance = truth_from_spec(GLOSSY, measured)
    assert luminance.label == f"the model {GLOSSY}"
    np.testing.assert_allclose(luminance.eval(pairs.wi, pairs.wo), rgb @ LUMINANCE, rtol=1e-15)
    green = truth_from_spec(GLOSSY, replace(measured, band="g"))
    np.testing.assert_array_equal(green.eval(pairs.wi, pairs.wo), rgb[:, 1])
    colour = truth_from_spec(GLOSSY, replace(measured, band="rgb"))
    np.testing.assert_array_equal(colour.eval(pairs.wi, pairs.wo), rgb)
    plain = truth_from_spec("lambert:albedo=0.5", measured)
    np.testing.assert_allclose(plain.eval(pairs.wi, pairs.wo), 0.5 / np.pi, rtol=1e-15)


@pytest.mark.parametrize("form", ["scene", "material", "nested"])
def test_a_material_or_scene_file(
    form: str, measured: Measured, pairs: testset.TestSet, tmp_path: Path
) -> None:
    path = SCENES / "matte.yaml"
    if form != "scene":
        path = tmp_path / "paint.yml"
        params = "alpha: 0.5, distribution: ggx, fresnel: schlick, f0: 0.04, kd: 0.6"
        body = params.replace(", ", "\n") if form == "material" else f"params: {{{params}}}"
        path.write_text(f"name: cook_torrance\n{body}\n")
    truth = truth_from_spec(str(path), measured)
    assert truth.label == f"the material of {path}"
    np.testing.assert_allclose(
        truth.eval(pairs.wi, pairs.wo), measured.scene_truth()(pairs.wi, pairs.wo), rtol=1e-15
    )


def test_another_run_is_reconstructed(
    run: Path, measured: Measured, pairs: testset.TestSet
) -> None:
    built: list[Measured] = []

    def reconstruct(other: Measured) -> NaiveReconstruction:
        built.append(other)
        return NaiveReconstruction(other)

    truth = truth_from_spec(str(run), measured, reconstruct=reconstruct)
    assert [m.source for m in built] == [str(run)]
    assert truth.label == f"the reconstruction of {run}"
    assert truth.supported is not None
    naive = NaiveReconstruction(measured)
    np.testing.assert_array_equal(truth.eval(pairs.wi, pairs.wo), naive.eval(pairs.wi, pairs.wo))
    with pytest.raises(GonioError, match="needs a way to reconstruct it"):
        truth_from_spec(str(run), measured)


@pytest.mark.parametrize(
    ("spec", "says"),
    [
        ("velvet", "truth 'velvet': unknown BRDF model 'velvet'; expected one of lambert"),
        ("lambert:albedo", "truth 'lambert:albedo': expected NAME:key=value"),
        ("lambert:albedo=2", "truth 'lambert:albedo=2': a reflectance is at most 1"),
        ("lambert:colour=1", "lambert: unknown parameter(s) colour"),
        ("lambert:albedo=[0.1", "albedo: cannot read the value '[0.1'"),
        ("runs/missing.sqlite", "runs/missing.sqlite: no such file, and not a model"),
        ("missing.yaml", "missing.yaml: cannot read it (No such file or directory)"),
    ],
)
def test_a_spec_that_names_nothing_usable_is_one_line(
    spec: str, says: str, measured: Measured
) -> None:
    with pytest.raises(GonioError) as error:
        truth_from_spec(spec, measured)
    assert says in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("name: a: b\n", "bad.yaml:1: not valid YAML (mapping values are not allowed here)"),
        ("seed: 3\n", "bad.yaml: expected a material (name: MODEL and its parameters)"),
        ("material: {name: lambert, albedo: 7}\n", "bad.yaml: material: a reflectance"),
        ("name: lambert\nparams: [1]\n", "bad.yaml: material.params: expected a mapping"),
    ],
)
def test_a_bad_material_file_is_one_line(
    text: str, says: str, measured: Measured, tmp_path: Path
) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(GonioError) as error:
        truth_from_spec(str(path), measured)
    assert says in str(error.value) and "\n" not in str(error.value)
