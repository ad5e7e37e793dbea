"""Suite-wide settings (hypothesis profiles, derandomized under CI; the xdist groups) and
the fixtures shared across packages: the shipped rigs, a virtual clock, emulated
Dynamixel buses and the in-process `gonio` command (helper functions shared across
packages: tests/support)."""

from __future__ import annotations

import os

# One BLAS thread per test process, set before numpy or scipy loads theirs (the processes
# the tests start inherit it). OpenBLAS's threads spin while they wait for work: with
# three workers on two cores, each with a pool of its own, they took the cores from each
# other (a Delaunay test took 50 s beside two busy processes, 2 s with one thread each).
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import signal
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from dynamixel_sdk import port_handler
from hypothesis import HealthCheck, settings

from gonio.rig.model import Rig
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator
from tests.support.priority import ahead

#: The shipped configuration files.
CONFIGS = Path(__file__).resolve().parents[1] / "configs"
#: The shipped rigs by short name (the files in configs/rigs).
RIG_FILES = {"arch": CONFIGS / "rigs" / "arch.yaml", "in_plane": CONFIGS / "rigs" / "in_plane.yaml"}
#: Their short names, for parametrize lists at collection time (load them with `rigs`).
RIG_NAMES = list(RIG_FILES)
#: The arch rig with a point source instead of its beam (the point-source scene's rig).
ARCH_POINT_FILE = CONFIGS / "rigs" / "arch_point.yaml"

# A suite started in the background of a non-interactive shell (as a CI runner may start
# it) inherits SIGINT ignored, and Python then installs no KeyboardInterrupt handler: the
# Ctrl-C tests need one, and their child processes need the signal not ignored (an
# ignored signal stays ignored across exec, a handled one does not).
signal.signal(signal.SIGINT, signal.default_int_handler)

settings.register_profile(
    "dev", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
# CI: derandomized, and lean — every property is also pinned at its extremes by named
# cases, so 50 examples per property keep the search honest within the time budget.
settings.register_profile(
    "ci",
    max_examples=50,
    deadline=None,
    derandomize=True,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
# A long search, for a release or after touching the math: HYPOTHESIS_PROFILE=thorough.
settings.register_profile(
    "thorough", max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile(
    os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") else "dev")
)


#: The SDK's packet timeouts scale with LATENCY_TIMER (ms): 2 × it + 2 ms + the reply's
#: wire time. The SDK busy-waits for replies in the test's thread while the emulator
#: serves from another thread of the same process; when the machine is busy (the other
#: test workers, or a shared host) the OS can preempt the SDK's thread while it holds the
#: GIL, and the SDK's default (16, a 34 ms budget) turned into rare timeouts of raw SDK
#: calls, which have no retries. 50 gives 102 ms; the expected timeouts cost ~4 s in all.
#: The SDK's global is what plain SDK ports use; a `DynamixelLink` never reads or writes
#: it (its port has its own timer: pass ``latency_ms``).
TEST_LATENCY_TIMER = 50


@dataclass(frozen=True)
class CliResult:
    """What a ``gonio`` command did: its exit code and what it printed."""

    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def run_gonio(capsys: pytest.CaptureFixture[str]) -> Callable[..., CliResult]:
    """Run ``gonio ARGS…`` in-process (`gonio.cli.main`), as the console script would:
    argparse's usage errors exit with 2, which is caught and returned as the code."""
    from gonio.cli import main

    def run(*args: str) -> CliResult:
        capsys.readouterr()
        try:
            code = main(list(args))
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        out = capsys.readouterr()
        return CliResult(code, out.out, out.err)

    return run


@pytest.fixture(scope="session")
def rigs() -> dict[str, Rig]:
    """The shipped rigs, loaded once per session."""
    return {name: Rig.from_yaml(path) for name, path in RIG_FILES.items()}


@pytest.fixture(params=RIG_NAMES)
def rig(request: pytest.FixtureRequest, rigs: dict[str, Rig]) -> Rig:
    """Each shipped rig in turn."""
    return rigs[request.param]


@pytest.fixture(scope="session")
def arch_point() -> Rig:
    """The arch rig with a point source (configs/rigs/arch_point.yaml), loaded once."""
    return Rig.from_yaml(ARCH_POINT_FILE)


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock()


@pytest.fixture
def emulator(clock: ManualClock) -> Iterator[Callable[..., DxlEmulator]]:
    """Factory: a started emulator (fast by default: no wire time, no return delay, the
    test's ManualClock); stopped after the test, which fails if serving raised."""
    started: list[DxlEmulator] = []

    def make(ids: tuple[int, ...] = (1,), **kwargs: Any) -> DxlEmulator:
        kwargs.setdefault("clock", clock)
        kwargs.setdefault("wire_time", False)
        kwargs.setdefault("return_delay", False)
        emu = DxlEmulator(ids=ids, **kwargs)
        emu.start()
        started.append(emu)
        return emu

    yield make
    for emu in started:
        emu.stop()
    for emu in started:
        assert emu.error is None, f"the emulator raised while serving: {emu.error!r}"


@pytest.fixture
def latency_timer(monkeypatch: pytest.MonkeyPatch) -> int:
    """Pin the SDK's LATENCY_TIMER for the test (and restore it after)."""
    monkeypatch.setattr(port_handler, "LATENCY_TIMER", TEST_LATENCY_TIMER)
    return TEST_LATENCY_TIMER


#: Tests that talk to a pseudo-terminal (the emulated bus, the photometer, the lamp): the
#: test's thread waits for replies while the device serves from another (the unmodified
#: SDK's own port spinning as it waits, the link's in `select`: `sdk_boundary.Port`;
#: `sim.peers.responsive` keeps that hand-off short). They (and any test marked ``pty`` by
#: hand) are marked ``pty`` and kept in one xdist group, so `make test` runs them one
#: after another on a single worker (and one worker at a time raises its session's
#: priority: `real_time_first`); the other workers' CPU-bound tests load the machine as
#: an unquiet host would (they held on a 2-core machine loaded 150 %).
PTY_TESTS = (
    "tests/drivers/",
    "tests/sim/peers/dynamixel/",
    "tests/sim/peers/test_serial_photometer.py",
    "tests/sim/virtual/devices/test_rehearsal.py",
    "tests/gonio/cli/test_motors.py",
    "tests/gonio/cli/test_detector.py",
    "tests/gonio/workflows/test_hardware.py",
    "tests/gonio/acquire/test_fly_rehearsal.py",
)


#: Whether pty tests run at a raised priority. Off: in a clean-clone `make test` on the
#: shared 2-core machine, five pty tests failed with it on (replies missing, the SDK's
#: spinning wait at nice -20 likely starving the kernel's pty hand-off); they passed
#: without it in the runs before.
RAISE_PTY_PRIORITY = False


@pytest.fixture(autouse=True)
def real_time_first(request: pytest.FixtureRequest) -> Iterator[None]:
    """A ``pty`` test runs ahead of the host's other work (`tests.support.priority`): its
    thread, the emulators' threads and the processes it starts get the CPU first, so a
    loaded machine cannot hold a device's reply past the protocol's deadline (as root,
    as CI runs; elsewhere at the priority the suite has)."""
    if request.node.get_closest_marker("pty") is None or not RAISE_PTY_PRIORITY:
        yield
        return
    with ahead():
        yield


#: Modules whose tests share a costly module- or session-scoped fixture (a second or more
#: on a loaded machine), by the xdist group they form. xdist sends a group to one worker,
#: which builds the fixture once; spread over the workers, each would build its own.
SHARED_SETUP = {
    "tests/gonio/brdf/test_factored.py": "factored-tables",
    "tests/gonio/brdf/test_merl.py": "merl-tables",
    "tests/gonio/cli/test_evaluate.py": "evaluated-run",
    "tests/gonio/cli/test_fit.py": "fitted-runs",
    "tests/gonio/cli/test_plot.py": "plotted-run",
    "tests/gonio/export/test_alta.py": "alta-files",
    "tests/gonio/export/test_factored.py": "factored-export",
    "tests/gonio/export/test_merl.py": "merl-export",
    "tests/gonio/planner/test_plan.py": "small-plans",
    "tests/gonio/reconstruct/test_fit.py": "long-runs",
    "tests/gonio/store/test_run_fuzz.py": "fuzzed-run",
    "tests/gonio/test_damaged_files.py": "damaged-files",
    "tests/gonio/tradeoff/test_executors.py": "reference-sweep",
    "tests/gonio/tradeoff/test_sweep.py": "reference-sweep",
    "tests/sim/virtual/test_simulate.py": "shipped-plans",
    "tests/studies/brdf/test_lobe_anisotropy.py": "lobe-widths",
}


# Before xdist's hook, which writes each test's xdist_group into the node id it schedules
# by (registered after this file, it would otherwise run first and see no group).
@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    root = Path(config.rootpath)
    for item in items:
        where = item.path.relative_to(root).as_posix()
        if (
            where.startswith(PTY_TESTS)
            or "emulator" in getattr(item, "fixturenames", ())
            or item.get_closest_marker("pty") is not None
        ):
            item.add_marker(pytest.mark.pty)
            item.add_marker(pytest.mark.xdist_group("pty"))
        elif where in SHARED_SETUP:
            item.add_marker(pytest.mark.xdist_group(SHARED_SETUP[where]))
