"""Runs of `gonio acquire` for the acquisition and journal tests: small plan and scene
files written into a folder (a plan file with its rig, built once), a run acquired on
the simulated backend into a real SQLite file, an acquiring child process (`os.fork`)
that reports every target it finishes through a pipe and can be killed at any moment,
and what a run file holds, for bit-for-bit comparisons."""

from __future__ import annotations

import os
import select
import signal
import sqlite3
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from gonio.planner.files import PlanSource, load_plan_source
from gonio.planner.model import Plan
from gonio.scene import Scene
from gonio.store.read import Run
from gonio.workflows import session

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
ARCH = CONFIGS / "rigs" / "arch.yaml"
#: Noise, backlash, repeatability, ticks and a drifting source: every random stream and
#: the motors' state matter, so a resume that restored anything wrong shows.
BRUSHED = CONFIGS / "scenes" / "brushed_metal.yaml"


def plan_yaml(
    targets: int = 60, *, rig: Path = ARCH, acquisition: dict[str, Any] | None = None
) -> str:
    """A small Sobol plan on ``rig``: calibrations every 15 targets, health every 10."""
    spec: dict[str, Any] = {
        "name": "crash",
        "rig": str(rig),
        "parametrization": "hybrid",
        "isotropic": True,
        "sampling": {"strategy": "sobol", "target": targets, "seed": 1},
        "exposure": {"seconds": 0.05, "averages": 2},
        "time_budget_s": 5,
        "acquisition": {
            "calibration": {"every_samples": 15, "averages": 4},
            "health": {"every_samples": 10},
            **(acquisition or {}),
        },
    }
    return yaml.safe_dump(spec, sort_keys=False)


def scene_yaml(faults: list[dict[str, Any]] | None = None, base: Path = BRUSHED) -> str:
    spec = yaml.safe_load(base.read_text())
    if faults is not None:
        spec["faults"] = faults
    return yaml.safe_dump(spec, sort_keys=False)


_PLANS: dict[tuple[str, str], Plan] = {}


@dataclass(frozen=True)
class RunFiles:
    """A plan file and a scene file (written by the `run_files` fixture)."""

    plan: Path
    scene: Path

    def files(self) -> tuple[Plan, session.Files, Any]:
        """(the plan, planned once per plan text and rig, the files, the scene)."""
        source = load_plan_source(self.plan)
        key = (source.text.decode(), source.rig.text.decode())
        if key not in _PLANS:
            _PLANS[key] = source.build()
        scene, text = session.load_scene_file(self.scene, source.rig)
        files = session.Files(
            source.path, source.text, source.rig.source, source.rig.text, self.scene, text
        )
        return _PLANS[key], files, scene

    def start(self, output: Path | None, **kwargs: Any) -> session.SessionResult:
        plan, files, scene = self.files()
        return session.start(plan, files, scene=scene, output=output, **kwargs)

    def cli(self, output: Path) -> list[str]:
        """``gonio`` arguments that start this run into ``output``."""
        return ["acquire", str(self.plan), "--scene", str(self.scene), "-o", str(output), "-q"]


def sample_values(run: Run) -> dict[str, np.ndarray]:
    """Every column of a run's samples that a resume must not change: all but the
    session, the wall-clock time and the attempts (a retried sample resumed after its
    failed attempt counts only the attempts of its session)."""
    skip = {"session", "utc", "attempts"}
    return {k: v for k, v in run.samples.items() if k not in skip}


def calibration_values(run: Run) -> list[tuple[Any, ...]]:
    """Each calibration's readings, counts and run times."""
    return [
        (e.data["k"], e.data["count"], e.t_s, dict(e.data["reference"]), dict(e.data["dark"]))
        for e in run.of_kind("calibration")
    ]


def assert_same_samples(run: Run, expected: Run) -> None:
    got, want = sample_values(run), sample_values(expected)
    assert got.keys() == want.keys()
    for name, value in want.items():
        if value.dtype == object:
            assert got[name].tolist() == value.tolist(), name
        else:
            np.testing.assert_array_equal(got[name], value, err_msg=name, strict=True)
    assert calibration_values(run) == calibration_values(expected)


def integrity(path: Path) -> str:
    """``PRAGMA integrity_check`` of a run file ('ok' when sound); never creates one."""
    conn = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
    try:
        return str(conn.execute("PRAGMA integrity_check").fetchone()[0])
    finally:
        conn.close()


#: How long a held child waits for its signal (the parent gives up sooner).
HOLD_S = 120.0


class PipeProgress:
    """A `gonio.acquire.observer.Observer` that writes ``t INDEX`` to a pipe for every
    target finished (called after its sample or skip was committed); with
    ``hold_after`` it waits, once it reported that many targets (over all sessions),
    for the signal the parent sends then, so the run cannot finish before it."""

    def __init__(self, fd: int, pause_s: float = 0.0, hold_after: int | None = None) -> None:
        self.fd = fd
        self.pause_s = pause_s  # wall time per target: a run slow enough to signal
        self.hold_after = hold_after
        self.reported = 0
        self.todo: list[int] = []

    def start(self, plan: Plan, todo: np.ndarray) -> None:
        self.todo = todo.tolist()

    def advance(self, done: int) -> None:
        os.write(self.fd, b"t %d\n" % self.todo[done - 1])
        self.reported += 1
        if self.hold_after is not None and self.reported >= self.hold_after:
            time.sleep(HOLD_S)
        if self.pause_s:
            time.sleep(self.pause_s)

    def close(self) -> None:
        pass


@dataclass
class ChildResult:
    """What a forked acquiring child did: the targets it reported finished, whether it
    was killed, and its last line (``done OUTCOME`` or ``error …``) if it got there."""

    reported: list[int] = field(default_factory=list)
    killed: bool = False
    last: str | None = None


def acquire_in_child(
    work: Callable[[PipeProgress], object],
    *,
    kill_after: int | None = None,
    delay_s: float = 0.0,
    kill_signal: int = signal.SIGKILL,
    timeout_s: float = 60.0,
    hold: bool = False,
) -> ChildResult:
    """Fork a child that runs ``work(progress)`` (a `session.SessionResult` is reported as its
    outcome, anything else as it is); the parent sends ``kill_signal`` once the child
    reported ``kill_after`` targets (None: never; 0: from the fork) and ``delay_s`` more
    seconds passed, and returns what the child reported; ``hold``: the child waits after
    reporting ``kill_after`` targets, so the signal lands right after that target."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns into the test
        code = 0
        try:
            os.close(r)
            value = work(PipeProgress(w, hold_after=kill_after if hold else None))
            if isinstance(value, session.SessionResult):
                value = value.report.outcome
            os.write(w, f"done {value}\n".encode())
        except BaseException as exc:
            os.write(w, f"error {type(exc).__name__}: {exc}\n".encode())
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    os.close(w)
    result = ChildResult()
    buf = b""
    deadline = time.monotonic() + delay_s if kill_after == 0 else None
    give_up = time.monotonic() + timeout_s
    try:
        while True:
            if deadline is None and kill_after and buf.count(b"t ") >= kill_after:
                deadline = time.monotonic() + delay_s
            now = time.monotonic()
            if deadline is not None and now >= deadline:
                os.kill(pid, kill_signal)
                result.killed = kill_signal == signal.SIGKILL
                break
            wait = min(give_up, deadline or give_up) - now
            assert wait > 0, "the acquiring child hung"
            ready, _, _ = select.select([r], [], [], wait)
            if ready:
                chunk = os.read(r, 65536)
                if not chunk:
                    break
                buf += chunk
        while chunk := os.read(r, 65536):
            buf += chunk
    finally:
        os.close(r)
        _, status = os.waitpid(pid, 0)
    if result.killed:
        result.killed = os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    for line in buf.decode().splitlines():
        if line.startswith("t "):
            result.reported.append(int(line.split()[1]))
        else:
            result.last = line
    return result


QUICK = CONFIGS / "plans" / "quick.yaml"
MATTE = CONFIGS / "scenes" / "matte.yaml"


def plan_file(
    folder: Path, *, target: int = 40, acquisition: str = "", name: str = "small"
) -> Path:
    """A plan file in ``folder``: the quick plan's sampling with ``target`` targets on
    the arch rig, with an ``acquisition:`` section (YAML text, indented by the caller
    at top level) if given."""
    rig = (CONFIGS / "rigs" / "arch.yaml").resolve()
    text = (
        f"name: {name}\nrig: {rig}\nparametrization: hybrid\nisotropic: true\n"
        f"sampling: {{strategy: sobol, target: {target}, seed: 1}}\n"
        "exposure: {seconds: 0.05, averages: 1}\n"
        f"{acquisition}"
    )
    path = folder / f"{name}.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@cache
def _built(path: str, text: bytes) -> tuple[PlanSource, Plan]:
    source = load_plan_source(Path(path))
    return source, source.build()


def build_plan(path: Path) -> tuple[PlanSource, Plan]:
    """(source, plan) of a plan file (cached by path and content)."""
    return _built(str(path), path.read_bytes())


def scene_file(folder: Path, extra: str = "", base: Path = MATTE, name: str = "scene") -> Path:
    """A scene file in ``folder``: ``base``'s text with ``extra`` YAML appended."""
    path = folder / f"{name}.yaml"
    path.write_text(base.read_text(encoding="utf-8") + extra, encoding="utf-8")
    return path


def acquire(
    plan_path: Path, scene_path: Path, output: Path | None, **kwargs: object
) -> session.SessionResult:
    """`session.start` of a plan file in a scene (what `gonio acquire` does)."""
    source, plan = build_plan(plan_path)
    scene, text = session.load_scene_file(scene_path, source.rig)
    files = session.Files(
        source.path, source.text, source.rig.source, source.rig.text, scene_path, text
    )
    return session.start(plan, files, scene=scene, output=output, **kwargs)  # type: ignore[arg-type]


def load(scene_path: Path) -> Scene:
    from gonio.scene import load_scene

    return load_scene(scene_path)
