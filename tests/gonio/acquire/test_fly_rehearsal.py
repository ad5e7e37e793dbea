"""Fly sweeps on the rehearsal path: the real `DynamixelBus` polling the byte-level
emulator's motion on its pty and the real `SerialDetector` streaming from the simulated
photometer on its pty, on the rehearsal's one scaled clock. The samples' merged joint
angles must lie within one encoder tick plus v·σt of the emulator's true trajectory at
the middle of the window the photometer really integrated (its own record of the
window's end), and a small fly plan must acquire through `gonio acquire --rehearse`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from drivers.serial_detector import SerialDetectorError
from gonio.acquire.fly import derive, run_sweep
from gonio.acquire.fly.merge import SLOW_POLL
from gonio.planner.files import load_plan_source
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.store import open_run
from gonio.workflows.rehearsal import rehearsal_devices
from sim.rehearsal import RehearsalSide
from tests.conftest import CONFIGS, CliResult

pytestmark = pytest.mark.pty

PLAN = CONFIGS / "plans" / "fly_rehearsal.yaml"
RIG = CONFIGS / "rigs" / "arch_serial.yaml"
SCENE = CONFIGS / "scenes" / "glossy_metal.yaml"
#: Slow enough that the host's real latencies (a poll's round trip, a line's delivery)
#: stay a few virtual milliseconds: they count `SPEEDUP` times on the rehearsal's clock.
SPEEDUP = 5.0


def test_merged_angles_follow_the_emulated_trajectory() -> None:
    source = load_plan_source(PLAN)
    plan, rig = source.build(), source.rig
    sweeps = plan.sweeps
    assert sweeps is not None
    tick = np.array([a.resolution_rad for a in rig.bus_axes()])
    with rehearsal_devices(rig, load_scene(SCENE), None, SPEEDUP) as (devices, clock):
        side = devices.simulation
        assert isinstance(side, RehearsalSide) and side.peers is not None
        photometer = side.peers.photometer
        assert photometer is not None
        with devices:
            for k in range(len(sweeps)):
                for attempt in range(2):
                    before = len(photometer.stream_ends)
                    try:
                        raw = run_sweep(devices, rig.axes, sweeps, k,
                                        settle_s=rig.spec.settle_s, timeout_s=30.0)  # fmt: skip
                    except SerialDetectorError as exc:
                        # A host stalled past the stream's timeout: as the engine does
                        # (`on_fault.retries`), hold every axis and fly the sweep again,
                        # once.
                        if attempt or exc.kind != "timeout":
                            raise
                        devices.bus.stop()
                        continue
                    # Every window the photometer integrated reached the host, in order.
                    ends = [clock.at(t) for t in photometer.stream_ends[before:]]
                    assert len(ends) == len(raw.readings)
                    d = derive(raw, rig.axes, sweeps, plan.arrival_s, k)
                    if len(d.samples.index) >= 0.5 * int(sweeps.count[k]):
                        break
                    # A loaded host polls less, and a window no two polls bracket closely
                    # is left out: a stall of the host (tens of polls' worth, counted
                    # SPEEDUP times on the clock) loses the rest of a sweep. Only such a
                    # stall excuses it, and only once.
                    gaps = np.diff(0.5 * (d.request + d.reply))
                    assert attempt == 0 and gaps.max() > 20 * np.median(gaps), (
                        k, len(d.samples.index), len(raw.polls), gaps.max(), np.median(gaps)
                    )  # fmt: skip
                # The truth at the middle of each window really integrated.
                middle = np.array(ends)[d.samples.index] - 0.5 * sweeps.integration_s
                truth = np.array(
                    [[side.true_pose_at(t)[a] for a in rig.axes] for t in middle.tolist()]
                )
                error = np.abs(d.samples.angles - truth)
                # v·σt as a bound: the two polls' and the stamps' uniform spreads summed at
                # worst (their quadrature σ times √3·√12 = 6).
                allowed = tick[None, :] + 6.0 * d.samples.timing[:, None]
                within = np.all(error <= allowed, axis=1)
                # (on a host loaded several times its cores, a few polls answer with a
                # position sampled before their request's stamp: at most a few percent)
                assert within.mean() >= 0.95, (k, within.mean(), (error / allowed).max())
                # Planned against measured velocity: the register's step (0.229 rev/min).
                j = int(np.argmax(np.abs(sweeps.velocity[k])))
                t = 0.5 * (d.request + d.reply)
                # (the polls a loaded host took long to answer sampled anywhere in their
                # span: left out, as the merge leaves them out of its interpolation)
                steady = (d.reply - d.request) <= SLOW_POLL * np.median(d.reply - d.request)
                cruise = (t > middle[0]) & (t < middle[-1]) & steady
                speed = np.polyfit(t[cruise], d.positions[cruise, j], 1)[0]
                assert speed / sweeps.velocity[k, j] == pytest.approx(1.0, abs=0.02)
                # the velocity the bus commanded is the register's, the one the motor runs
                assert raw.velocities is not None
                inner = middle[[1, -2]]  # a period in from each end: wholly cruising
                x0, x1 = (side.true_pose_at(float(t))[rig.axes[j]] for t in inner)
                run = abs(x1 - x0) / float(inner[1] - inner[0])
                assert run == pytest.approx(raw.velocities[rig.axes[j]], rel=1e-3)


def test_a_fly_plan_acquires_on_the_rehearsal_path(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    out = tmp_path / "run.sqlite"
    result = run_gonio(
        "acquire", str(PLAN), "--scene", str(SCENE), "--rehearse", "--speedup",
        str(SPEEDUP), "-o", str(out), "-q",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    run = open_run(out)
    assert run.meta["backend"] == "rehearsal" and run.complete
    sweeps = run.plan.sweeps
    assert sweeps is not None
    # every sweep measured once; one that kept fewer readings than asked (a host stall)
    # was journaled as abandoned, short, and redone within on_fault.retries
    assert [s.sweep for s in run.sweeps if s.outcome == "measured"] == list(range(len(sweeps)))
    assert all(s.data.get("short") for s in run.sweeps if s.outcome == "abandoned")
    assert len(run) >= 0.7 * len(run.plan)
    # The axes that do not sweep hold their commanded angles to a tick or two; the swept
    # one is read at mid-window, near its target (the velocity's register step drifts it
    # along the sweep by at most a few readings' travel), within what its timing σ says
    # (a loaded host answers its polls slowly: each position then belongs to a longer
    # span of time, and the sample says so).
    rig = Rig.from_yaml(RIG)
    tick = np.array([a.resolution_rad for a in rig.bus_axes()])
    gap = np.abs(run.angles("read_back") - run.angles("commanded"))
    swept = np.abs(sweeps.velocity).max(axis=0) > 0
    assert np.all(gap[:, ~swept] <= 2 * tick[~swept]), (gap[:, ~swept] / tick[~swept]).max()
    speed = float(np.abs(sweeps.velocity).max())
    timing = np.asarray(run.samples["timing_rad"], dtype=np.float64)
    bound = 5 * speed * sweeps.period_s + 6 * timing[:, None]
    assert np.all(gap[:, swept] <= bound), (gap[:, swept] / bound).max()


def test_a_plan_of_theta_h_lines_acquires_on_the_rehearsal_path(
    run_gonio: Callable[..., CliResult], tmp_path: Path
) -> None:
    plan = tmp_path / "lines.yaml"
    plan.write_text(
        PLAN.read_text()
        .replace("rig: ../rigs/", f"rig: {RIG.parent}/")
        .replace("target: 300", "target: 150")
        .replace("blur_deg: 0.5", "blur_deg: 1.0\n    segment: theta_h_line")
    )
    out = tmp_path / "run.sqlite"
    result = run_gonio(
        "acquire", str(plan), "--scene", str(SCENE), "--rehearse", "--speedup",
        str(SPEEDUP), "-o", str(out), "-q",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    run = open_run(out)
    sweeps = run.plan.sweeps
    assert sweeps is not None and sweeps.has_paths and run.complete
    assert [s.sweep for s in run.sweeps if s.outcome == "measured"] == list(range(len(sweeps)))
    assert len(run) >= 0.95 * len(run.plan)
    # every axis followed its trajectory: the read-back angles (the real DynamixelBus's
    # polls of the emulated motors, which the samples keep) near the planned ones, within
    # the tracking a loaded host allows (tens of mrad: docs/results/trajectory_bus.md)
    # and one reading period's travel, within what the readings' timing σ says (polls a
    # loaded host answers slowly place each reading less surely); a reading matched to a
    # wrong slot would be off by several periods' travel
    gap = np.abs(run.angles("read_back") - run.angles("commanded"))
    steps = [np.abs(np.diff(sweeps.set_points(k), axis=0)) for k in range(len(sweeps))]
    speed = np.concatenate(steps).max(axis=0) / sweeps.path_period_s
    timing = float(np.median(np.asarray(run.samples["timing_rad"], dtype=np.float64)))
    bound = speed * sweeps.period_s + 0.06 + 6 * timing
    assert np.all(np.median(gap, axis=0) <= bound), np.median(gap, axis=0) / bound
