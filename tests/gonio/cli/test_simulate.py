"""`gonio simulate`: a plan measured on the simulated rig, end to end, as a user runs it
(in-process through `gonio.cli.main`), and what its summary says."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio import brdf
from gonio.acquire.reference import reference_pose
from gonio.analysis.calibrated import calibrate
from gonio.analysis.summary import truth_of
from gonio.cli.simulate import render_result as render
from gonio.errors import GonioError
from gonio.export.factored import Resolution
from gonio.export.factored import export as export_factored
from gonio.planner import build, load_plan
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.store import open_run
from gonio.workflows.simulate import simulate_plan
from tests.conftest import CONFIGS, CliResult
from tests.support.acquire import plan_file
from tests.support.process import gonio_process
from tests.support.rigs import rig_with

Gonio = Callable[..., CliResult]


def test_simulate_writes_the_run_and_recovers_the_brdf(run_gonio: Gonio, tmp_path: Path) -> None:
    out = tmp_path / "run.sqlite"
    r = run_gonio(
        "simulate",
        str(CONFIGS / "plans" / "quick.yaml"),
        "--scene",
        str(CONFIGS / "scenes" / "matte.yaml"),
        "-o",
        str(out),
    )
    assert r.returncode == 0, r.stderr
    assert "scene 'matte' (effects: shot_noise, read_noise, dark_current" in r.stdout
    assert f"wrote 500 samples to {out}" in r.stdout
    run = open_run(out)
    assert len(run) == 500 and run.meta["backend"] == "simulated"
    error = np.abs(calibrate(run).brdf / truth_of(run) - 1)
    assert np.median(error) < 0.005  # shot and read noise at ~30 % of full well
    assert np.all(np.diff(run.samples["settled_s"]) > 0)


def test_without_output_nothing_is_written_and_it_says_so(
    run_gonio: Gonio, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    r = run_gonio(
        "simulate",
        str(CONFIGS / "plans" / "quick.yaml"),
        "--scene",
        str(CONFIGS / "scenes" / "matte.yaml"),
        "-q",
    )
    assert r.returncode == 0, r.stderr
    assert "nothing written: give -o RUN.sqlite to keep the run file" in r.stdout
    assert list(tmp_path.iterdir()) == []


def test_a_bad_scene_is_a_line_per_problem(run_gonio: Gonio, tmp_path: Path) -> None:
    scene = tmp_path / "scene.yaml"
    scene.write_text("name: x\nmaterial: {name: velvet}\n", encoding="utf-8")
    r = run_gonio("simulate", str(CONFIGS / "plans" / "quick.yaml"), "--scene", str(scene))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    lines = r.stderr.removeprefix("gonio: error: ").splitlines()
    assert len(lines) == 3 and all(line.startswith(f"{scene}:") for line in lines)
    assert lines[0] == f"{scene}:1: source: Field required"
    assert lines[2].startswith(f"{scene}:2: material.name: unknown BRDF model 'velvet'")


def test_a_point_source_plan_keeps_the_view_on_the_sample(arch_point: Rig) -> None:
    """25 mm seen on a 30 mm sample: the view leaves the sample beyond acos(25/30) =
    33.6°, so the plan measures no target beyond it; on a 60 mm sample, up to 65.4°."""
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    for sample_mm, edge_deg in ((30, 33.557), (60, 65.376)):
        rig = rig_with(arch_point, constraints={"sample_diameter_mm": sample_mm})
        plan = build(spec.model_copy(update={"kicks": 0}), rig)
        theta_o = np.degrees(np.arccos(plan.wo[:, 2]))
        assert theta_o.max() <= edge_deg and theta_o.max() > edge_deg - 3.0


def test_the_reference_standard_is_the_rigs(rigs: dict[str, Rig]) -> None:
    """Albedo and calibration geometry come from the rig file's reference section."""
    rig = rig_with(rigs["arch"], reference={"albedo": 0.9, "theta_i_deg": 10, "theta_o_deg": 40})
    spec, _ = load_plan(CONFIGS / "plans" / "quick.yaml")
    plan = build(spec, rig)
    scene = load_scene(CONFIGS / "scenes" / "glossy_metal.yaml").with_effects([])
    result = simulate_plan(plan, scene)
    first = result.run.of_kind("calibration")[0].data
    assert first["albedo"] == 0.9
    np.testing.assert_allclose(result.brdf, result.truth, rtol=1e-12)
    wi, wo = rig.forward(reference_pose(rig))
    np.testing.assert_allclose(np.degrees(np.arccos([wi[2], wo[2]])), [10.0, 40.0], atol=1e-9)


def test_an_unreachable_reference_geometry_is_one_line(rigs: dict[str, Rig]) -> None:
    rig = rig_with(rigs["arch"], reference={"theta_o_deg": 85})  # beyond θ max = 80°
    with pytest.raises(GonioError) as info:
        reference_pose(rig)
    assert str(info.value) == (
        "rig 'arch-4axis' cannot reach its reference geometry (0°/85°; theta max)"
    )


def test_a_scene_for_the_other_source_kind_is_one_line(run_gonio: Gonio) -> None:
    """The quick plan's rig has a collimated light; the seed000_specular scene (the
    specular test function of Barla, Belcour & Pacanowski 2015) gives a point
    source's intensity: refused at the scene's line, before anything is simulated."""
    scene = CONFIGS / "scenes" / "seed000_specular.yaml"
    r = run_gonio("simulate", str(CONFIGS / "plans" / "quick.yaml"), "--scene", str(scene))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    line = next(n for n, text in enumerate(scene.read_text().splitlines(), 1) if "source:" in text)
    assert f"{scene}:{line}: source.intensity_w_sr: the light of the rig file " in r.stderr
    assert "is collimated (light.kind); expected irradiance_w_m2" in r.stderr
    r = run_gonio(
        "simulate",
        str(CONFIGS / "plans" / "quick.yaml"),
        "--scene",
        str(scene),
        "--rig",
        str(CONFIGS / "rigs" / "arch_point.yaml"),
    )
    assert r.returncode == 0, r.stderr
    assert "on rig 'arch-point-4axis', scene 'seed000-specular' (effects: saturation)" in r.stdout


def test_a_footprint_or_view_that_overruns_the_sample_is_warned(
    rigs: dict[str, Rig], arch_point: Rig
) -> None:
    """A collimated beam's lit ellipse off the sample at the angles reached (here: the
    true angles moved toward grazing, as a position error near the edge would), and a
    point source's view past the sample's edge with the footprint effect on (without it
    the ideal chain reads the holder as sample): a warning with the count and the share."""
    import dataclasses

    spec, _ = load_plan(CONFIGS / "plans" / "quickstart.yaml")
    scene = load_scene(CONFIGS / "scenes" / "matte.yaml").with_effects([])
    result = simulate_plan(build(spec, rigs["arch"]), scene)
    assert "warning: at" not in render(result)  # the planner refused every overrun
    grazing = result.true_wi.copy()
    grazing[:10] = [np.sin(1.5), 0.0, np.cos(1.5)]  # 86°: 6 mm / cos θi > 30 mm
    text = render(dataclasses.replace(result, true_wi=grazing))
    assert (
        "  warning: at 10 of 300 targets (3.3 %) the beam's footprint leaves the sample or "
        "the detector's view at the angles reached: their readings miss light that the "
        "BRDF assumes"
    ) in text.splitlines()

    point_scene = load_scene(CONFIGS / "scenes" / "seed000_specular.yaml", arch_point)
    point = simulate_plan(build(spec, arch_point), point_scene.with_effects(["footprint"]))
    assert "warning: at" not in render(point)  # the planner refused every view off the sample
    past = point.true_wo.copy()
    past[:10] = [np.sin(0.7), 0.0, np.cos(0.7)]  # 40°: 25 mm / cos θo > 30 mm
    assert "warning: at" not in render(
        dataclasses.replace(point, true_wo=past, scene=point_scene.with_effects([]))
    )  # the ideal chain reads the holder as sample: nothing is missed
    lines = render(dataclasses.replace(point, true_wo=past)).splitlines()
    assert (
        "  warning: at 10 of 300 targets (3.3 %) the "
        "detector's field of view reaches past the sample's edge at the angles reached: "
        "their readings miss light that the BRDF assumes"
    ) in lines


@pytest.mark.parametrize("effects", [(), ("--no-effects",)])
def test_a_material_file_relative_to_its_scene_is_found_from_any_folder(
    run_gonio: Callable[..., CliResult],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    effects: tuple[str, ...],
) -> None:
    """The scene names its tabulated material relative to itself; `gonio simulate` run
    from another folder measures and scores it (with --no-effects the journaled scene is
    the spec written back, which named the file relative to the folder it ran in)."""
    folder = tmp_path / "scenes"
    folder.mkdir()
    grey = brdf.create("lambert", albedo=0.5)
    export_factored(grey, folder / "grey.txt", 1, 1, Resolution(8, 8, 8, 8, 16))
    text = (CONFIGS / "scenes" / "matte.yaml").read_text(encoding="utf-8")
    start = text.index("\nmaterial:") + 1
    end = text.index("\n", start)
    text = text[:start] + "material: {name: factored, path: grey.txt}" + text[end:]
    (folder / "s.yaml").write_text(text, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    r = run_gonio(
        "simulate",
        str(plan_file(tmp_path, target=20)),
        "--scene",
        "scenes/s.yaml",
        "-o",
        "run.sqlite",
        *effects,
    )
    assert r.returncode == 0, r.stderr
    assert "recovered BRDF error" in r.stdout


def test_a_run_the_reference_saturates_names_that_cause(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    """A full well so small that the reference standard saturates even at the shortest
    exposure: gonio simulate names the reference and the fix, as gonio acquire does (it
    used to say only that the run had no calibration reading)."""
    text = (CONFIGS / "scenes" / "matte.yaml").read_text(encoding="utf-8")
    scene = tmp_path / "tiny_well.yaml"
    scene.write_text(text.replace("full_well_e: 5.0e+7", "full_well_e: 2.0e+3"), encoding="utf-8")
    r = run_gonio("simulate", str(plan_file(tmp_path, target=20)), "--scene", str(scene))
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "the reference standard saturates the detector" in r.stderr
    assert "lower the source's power" in r.stderr


def test_a_run_that_measured_nothing_does_not_exit_0(tmp_path: Path) -> None:
    """A real process: the first target's axes never settle, the run ends with none
    measured; exit 3 and one line on stderr saying why."""
    spec = (CONFIGS / "scenes" / "matte.yaml").read_text().replace("../rigs/", f"{CONFIGS}/rigs/")
    scene = tmp_path / "scene.yaml"
    scene.write_text(spec + "faults:\n  - {kind: motion_timeout, at: [0]}\n")
    plan = plan_file(tmp_path, target=8)
    result = gonio_process("simulate", str(plan), "--scene", str(scene), "-q")
    assert result.returncode == 3, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines() == [
        "gonio: the run measured nothing (outcome fault, 0 of 8 targets): axes did not settle "
        "within 600 s (an axis is blocked: injected at sample 0); holding them"
    ]
