"""`gonio acquire --rehearse` end to end on the real driver path: the shipped rehearsal
plan on the arch rig wired to hardware (configs/rigs/arch_serial.yaml), the real SDK on
the Dynamixel emulator's pty, `SerialDetector` on the simulated photometer's pty and
`SerialLightSwitch` on the simulated lamp relay's, run in-process through the CLI. The
journal must hold what the emulated instrument really did: read-back angles within one
encoder tick of the commanded ones, directions from them by forward kinematics, and
calibrated BRDF values that are the scene's material within their own uncertainty."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from gonio.acquire.engine import Engine
from gonio.acquire.runtime import RunTime
from gonio.analysis.calibrated import calibrate
from gonio.planner.files import load_plan_source
from gonio.planner.model import Plan
from gonio.planner.stored import plan_bytes
from gonio.radiometry.bands import band_eval
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.store import open_run
from gonio.store.journal import Journal
from gonio.store.read import read_run
from gonio.workflows.rehearsal import rehearsal_devices
from sim.rehearsal import RehearsalSide
from tests.conftest import CONFIGS, CliResult

pytestmark = pytest.mark.pty

PLAN = CONFIGS / "plans" / "rehearsal.yaml"
RIG = CONFIGS / "rigs" / "arch_serial.yaml"
SCENE = CONFIGS / "scenes" / "matte.yaml"
#: Time runs this much faster than real time: moves, settle dwells and exposures of a
#: target take about 1 ms of wall time; the serial round trips do not shrink.
SPEEDUP = "1000"


def test_a_rehearsed_run_journals_what_the_emulated_instrument_did(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    out = tmp_path / "rehearsal.sqlite"
    result = run_gonio(
        "acquire",
        str(PLAN),
        "--scene",
        str(SCENE),
        "--rehearse",
        "--speedup",
        SPEEDUP,
        "-o",
        str(out),
        "-q",
    )
    assert result.returncode == 0, result.stderr
    assert "rehearsal backend" in result.stdout
    run = open_run(out)
    rig = Rig.from_yaml(RIG)
    assert run.meta["backend"] == "rehearsal" and run.meta["rig_name"] == rig.spec.name
    assert run.complete and len(run) == len(run.plan) == 30

    # Read back from the emulated encoders: the commanded angle to within one tick.
    tick = np.array([a.resolution_rad for a in rig.bus_axes()])
    read_back, commanded = run.angles("read_back"), run.angles("commanded")
    assert np.all(np.abs(read_back - commanded) <= tick)
    assert np.any(read_back != commanded)  # really quantized, not copied
    # Directions are the forward kinematics of the read-back angles.
    wi, wo = run.directions()
    fk_wi, fk_wo = rig.forward(read_back)
    np.testing.assert_array_equal(wi, fk_wi)
    np.testing.assert_array_equal(wo, fk_wo)

    # The reference and dark readings went through the photometer and the lamp relay.
    calibrations = run.of_kind("calibration")
    assert [c.data["why"] for c in calibrations] == ["start", "end"]
    for c in calibrations:
        reference, dark = c.data["reference"], c.data["dark"]
        assert reference["n"] == dark["n"] == 16 and not reference["saturated"]
        assert dark["value"] < 0.01 * reference["value"]  # lamp off: dark current only

    # Calibrated BRDF values: the scene's material at the pairs measured, within noise.
    scene = load_scene(SCENE)
    truth = band_eval(scene.material.model(), scene.detector.band)(wi, wo)
    calibrated = calibrate(run)
    z = (calibrated.brdf - truth) / calibrated.sigma
    assert np.all(calibrated.sigma > 0) and np.all(calibrated.sigma < 0.02 * truth)
    assert np.max(np.abs(z)) < 4.5, z
    assert np.mean(z**2) < 2.5, z  # χ²/n near 1: the uncertainty is the noise


def test_a_rehearsal_without_a_scene_is_one_line(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    out = tmp_path / "rehearsal.sqlite"
    result = run_gonio("acquire", str(PLAN), "--rehearse", "-o", str(out), "-q")
    assert result.returncode == 2
    rig = PLAN.parent / "../rigs/arch_serial.yaml"
    assert result.stderr == (
        f"gonio: error: {rig}: --rehearse simulates what the detector sees: give --scene\n"
    )
    assert not out.exists()


class _RefuseAtTheEnd:
    """Progress that makes the lamp relay refuse every switch once the last target is
    measured (the end calibration's dark reading then cannot switch the light off)."""

    def __init__(self, side: RehearsalSide) -> None:
        self.side = side

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        self.last = len(todo)

    def advance(self, done: int) -> None:
        if done == self.last:
            assert self.side.peers.lamp is not None
            self.side.peers.lamp.refuse(100)

    def close(self) -> None:
        pass


def test_a_light_that_fails_in_a_calibration_ends_the_run_resumable(tmp_path: Path) -> None:
    """A `LightError` (any driver fault) outside a target's retry loop is journaled as a
    fault and ends the session resumable, with the axes held, as a motor fault does."""
    source = load_plan_source(PLAN)
    plan = source.build()
    with rehearsal_devices(source.rig, load_scene(SCENE), None, 1000.0) as (devices, clock):
        side = devices.simulation
        assert isinstance(side, RehearsalSide)
        meta = {"axes": list(source.rig.axes), "coordinate_names": list(plan.coordinate_names)}
        path = tmp_path / "run.sqlite"
        with Journal.create(path, meta, plan_bytes(plan), durable=False) as journal:
            journal.start_session("now", {})
            engine = Engine(
                plan, devices, journal, side, RunTime(clock.now), progress=_RefuseAtTheEnd(side)
            )
            report = engine.run()
            run = read_run(journal.conn, path)
    assert report.outcome == "fault"
    assert report.message.startswith("light switch") and "'OFF' was not acknowledged" in (
        report.message
    )
    assert len(run) == len(plan) and not run.complete  # every sample kept; resumable
    (fault,) = run.of_kind("fault")
    assert fault.data["error"] == "LightError"
    assert run.sessions[-1].outcome == "fault"


def test_the_exposure_journaled_is_the_one_the_device_integrated(tmp_path: Path) -> None:
    """The rig's photometer takes whole milliseconds: a plan asking 1.5 ms gets 2 ms.
    The journal says 2 ms (the reading's `exposure_s`), so the calibrated BRDF is right;
    with the exposure asked it would come out a third too high."""
    from gonio.workflows import session

    source = load_plan_source(PLAN)
    plan = source.build()
    import dataclasses

    plan = dataclasses.replace(plan, exposure_s=np.full(len(plan), 0.0015))
    scene, text = session.load_scene_file(SCENE, source.rig)
    files = session.Files(source.path, source.text, source.rig.source, source.rig.text, SCENE, text)
    out = tmp_path / "run.sqlite"
    session.start(plan, files, scene=scene, output=out, rehearse=True, speedup=1000.0)
    run = open_run(out)
    assert np.all(run.samples["exposure_s"] == 0.002)
    wi, wo = run.directions()
    truth = band_eval(scene.material.model(), scene.detector.band)(wi, wo)
    calibrated = calibrate(run)
    assert np.median(np.abs(calibrated.brdf / truth - 1)) < 0.05
