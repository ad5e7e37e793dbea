"""The engine's samples against the simulator's own target-by-target run (the
vectorized `sim.virtual.simulate.simulate` is the fast reference of the engine's results).

What can be compared exactly: the engine always reads the reference standard at the
start and on its schedule, which moves the motors (backlash direction, repeatability
draws) and advances the clock, so a run from home (`simulate`) is not the engine's run.
Between two calibrations, though, the engine measures consecutive plan targets exactly
as `SimulatedInstrument.run` does. So each stretch of the engine's run is measured again
by a fresh instrument restored from the snapshot journaled with the calibration before
it, and must agree bit for bit (counts, std, read-back angles, settle and end times,
saturation, directions from the read-back angles). `SimulatedInstrument.run` equals
`simulate` bit for bit on the same plan from the same state
(tests/sim/virtual/test_simulate.py), which closes the chain to the vectorized reference."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sim.virtual.devices.instrument import SimulatedInstrument
from tests.support.acquire import RunFiles
from tests.support.measure import measure_targets


def test_each_stretch_between_calibrations_equals_the_simulators_run(
    run_files: Callable[..., RunFiles],
) -> None:
    # Saturated readings kept as they are: the engine would measure them again at a
    # shorter exposure (time and draws the instrument's run does not spend).
    files = run_files(acquisition={"saturation": {"remeasure": False}})
    plan, _, scene = files.files()
    run = files.start(None).run
    assert run.complete and len(run) == len(plan)
    calibrations = run.of_kind("calibration")
    counts = [int(c.data["count"]) for c in calibrations]
    assert counts == [0, 15, 30, 45, 60]
    axes = plan.rig.axes
    s = run.samples
    for calibration, start, stop in zip(calibrations, counts, counts[1:], strict=False):
        with SimulatedInstrument(scene, plan.rig) as instrument:
            instrument.restore(calibration.data["sim_state"])
            alone = measure_targets(instrument, plan, start=start, stop=stop)
        rows = slice(start, stop)  # targets measured in the plan's order
        np.testing.assert_array_equal(s["target"][rows], np.arange(start, stop))
        read_back = np.stack([s[f"{a}_read_back_rad"][rows] for a in axes], axis=1)
        np.testing.assert_array_equal(read_back, alone.read_back, strict=True)
        np.testing.assert_array_equal(s["counts"][rows], alone.value, strict=True)
        np.testing.assert_array_equal(s["counts_std"][rows], alone.std, strict=True)
        np.testing.assert_array_equal(s["settled_s"][rows], alone.settled_s, strict=True)
        np.testing.assert_array_equal(s["ended_s"][rows], alone.end_s, strict=True)
        np.testing.assert_array_equal(s["saturated"][rows], alone.saturated, strict=True)
        wi, wo = plan.rig.forward(alone.read_back)
        np.testing.assert_array_equal(run.directions()[0][rows], wi, strict=True)
        np.testing.assert_array_equal(run.directions()[1][rows], wo, strict=True)
    assert not s["remeasured"].any()
