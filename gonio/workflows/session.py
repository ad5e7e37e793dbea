"""Starting, resuming and checking a run: files → backend → journal → engine.

`start` plans (or reads a stored plan), creates and locks the run file before anything
moves, and runs the engine. `resume` reopens a run file, checks that the plan, rig and
scene files it was made from are unchanged (by hash; ``force`` accepts a change and
journals it), and measures exactly the targets still missing from the stored plan,
which it never re-plans. What either checks first, and `dry_run`, which checks
everything a run needs without moving: `gonio.workflows.preflight`. Either calls its
``on_ready`` once every check has passed and the run file is open, before anything is
measured: what a caller writes or prints about the run (its control token) comes after
every refusal.
"""

from __future__ import annotations

import getpass
import hashlib
import os
import platform
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from drivers.errors import DriverError
from gonio import __version__
from gonio.acquire import Engine, Observer, Report, StopRequests, Unobserved, utc_now
from gonio.analysis import Measured
from gonio.config import ConfigError, load, read_bytes
from gonio.errors import GonioError
from gonio.planner import Plan, Survey, extend, parse_plan, plan_bytes, sha256
from gonio.rig import Rig, RigSpec, named_alignment
from gonio.scene import Scene, load_scene
from gonio.store import Journal, JournalError, Run, read_run, remove_run_file
from gonio.workflows import backends, hygiene
from gonio.workflows.adaptive import estimate
from gonio.workflows.backends import BackendKind
from gonio.workflows.preflight import Files, check_output, check_scene, preflight, refuse_fly


def load_scene_file(path: Path, rig: Rig) -> tuple[Scene, bytes]:
    """(scene, its bytes)."""
    raw = read_bytes(path)
    return load_scene(path, rig, raw=raw), raw


def _versions() -> dict[str, str]:
    out = {"gonio": __version__, "python": platform.python_version()}
    for name in ("numpy", "scipy", "pydantic", "dynamixel-sdk", "pyserial"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def _meta(
    plan: Plan, files: Files, kind: BackendKind, seed: int | None, started: float, **extra: Any
) -> dict[str, Any]:
    return {
        "plan_name": plan.spec.name,
        "rig_name": plan.rig.spec.name,
        "backend": kind,
        "seed": seed,
        "created_utc": utc_now(),
        "started_unix": started,
        "host": socket.gethostname(),
        "user": getpass.getuser(),
        "versions": _versions(),
        "axes": list(plan.rig.axes),
        "coordinate_names": list(plan.coordinate_names),
        "plan_path": None if files.plan_path is None else str(files.plan_path.resolve()),
        "rig_path": None if files.rig_path is None else str(files.rig_path.resolve()),
        "scene_path": None if files.scene_path is None else str(files.scene_path.resolve()),
        "plan_text": files.plan_text.decode("utf-8"),
        "rig_text": files.rig_text.decode("utf-8"),
        "scene_text": None if files.scene_text is None else files.scene_text.decode("utf-8"),
        "hashes": files.hashes(),
        **_alignment_meta(plan.rig),
        **extra,
    }


def _alignment_meta(rig: Rig) -> dict[str, Any]:
    """The alignment file the rig file names, as the run stores it beside the rig file's
    text (nothing without one: the run's meta as before alignments)."""
    if rig.alignment_text is None or rig.alignment_path is None:
        return {}
    return {
        "alignment_path": str(rig.alignment_path.resolve()),
        "alignment_text": rig.alignment_text.decode("utf-8"),
        "alignment_sha256": hashlib.sha256(rig.alignment_text).hexdigest(),
    }


def _session_info(kind: BackendKind, argv: list[str]) -> dict[str, Any]:
    return {"backend": kind, "pid": os.getpid(), "host": socket.gethostname(), "argv": argv}


@dataclass
class SessionResult:
    """What `start` or `resume` did: the engine's report (counts summed over an adaptive
    plan's passes), the run file, and the journal as it stands after the session."""

    report: Report
    path: Path | None
    run: Run  # the journal as it stands after the session


def _run_engine(
    journal: Journal,
    plan: Plan,
    backend: backends.Backend,
    history: Run | None,
    *,
    progress: Observer,
    retry_skipped: bool = False,
    argv: list[str],
) -> SessionResult:
    """Run the engine on what is missing; an adaptive plan's survey, once measured, is
    followed by its second pass (`_second_pass`) in a new session."""
    path = journal.path or Path(":memory:")
    measured = skipped = 0
    while True:
        journal.start_session(utc_now(), _session_info(backend.kind, argv))
        engine = Engine(
            plan=plan,
            devices=backend.devices,
            journal=journal,
            stage=backend.stage,
            time=backend.time,
            history=history,
            calibrate_on_resume=backend.calibrate_on_resume,
            retry_skipped=retry_skipped,
            progress=progress,
            stops=StopRequests(),
        )
        report = engine.run()
        measured, skipped = measured + report.measured, skipped + report.skipped
        run = read_run(journal.conn, path)
        if report.outcome != "completed" or not plan.is_survey:
            report = replace(report, measured=measured, skipped=skipped)
            return SessionResult(report, journal.path, run)
        plan = _second_pass(journal, run)
        history = read_run(journal.conn, path)


def _second_pass(journal: Journal, run: Run) -> Plan:
    """The adaptive plan's second pass planned from the survey's samples in the journal
    (`gonio.planner.two_pass`, steered by `gonio.workflows.adaptive.estimate`), stored in
    the run in place of the survey's plan (one statement: a crash leaves either) and
    journaled; the whole plan."""
    model = run.plan.spec.sampling.options().model
    measured = Measured.from_run(run)
    survey = Survey(run.plan.summary.requested, measured.wi, measured.wo, measured.f)
    whole = extend(run.plan, estimate(measured, model), survey, where=str(run.path))
    journal.replace_plan(plan_bytes(whole))
    t_s = float(np.max(run.samples["ended_s"])) if len(run) else 0.0
    detail = {"survey": len(run.plan), "targets": len(whole), "placed": whole.summary.second_pass}
    journal.event("second_pass", t_s, utc_now(), detail)
    return whole


def start(
    plan: Plan,
    files: Files,
    *,
    scene: Scene | None = None,
    output: Path | None,
    overwrite: bool = False,
    seed: int | None = None,
    rehearse: bool = False,
    speedup: float = 50.0,
    progress: Observer | None = None,
    argv: list[str] | None = None,
    max_page_count: int | None = None,
    force_simulated: bool = False,
    on_ready: Callable[[], None] | None = None,
) -> SessionResult:
    """Acquire ``plan`` into a new run file ``output`` (None: in memory);
    ``force_simulated``: the simulated backend whatever the rig's bus (`gonio simulate`);
    ``on_ready``: called once the run file is created, before anything moves (if it
    raises, the run file is removed)."""
    rig = plan.rig
    kind = check_scene(files, rig, scene, rehearse=rehearse, force_simulated=force_simulated)
    refuse_fly(plan, kind, scene)
    if seed is None and scene is not None:
        seed = int(scene.seed)
    check_output(output, overwrite, files)
    started = time.time()
    backend = backends.build(
        kind, rig, scene, seed, started, speedup=speedup, any_detector=force_simulated
    )
    try:
        hygiene.warn(preflight(plan, backend, files.plan_path))
    except GonioError:
        backend.close()
        raise
    meta = _meta(
        plan,
        files,
        kind,
        seed,
        started,
        speedup=speedup if rehearse else None,
        any_detector=force_simulated,
    )
    stored = plan_bytes(plan)
    try:
        parse_plan(stored, "plan")  # a plan the journal could not give back is refused now
        with Journal.create(
            output,
            meta,
            stored,
            durable=backend.durable,
            overwrite=overwrite,
            max_page_count=max_page_count,
        ) as journal:
            if on_ready is not None:
                try:
                    on_ready()
                except BaseException:
                    journal.close()
                    if output is not None:
                        remove_run_file(output)
                    raise
            try:
                return _run_engine(
                    journal, plan, backend, None, progress=progress or Unobserved(), argv=argv or []
                )
            except DriverError:
                # The devices could not be opened (port missing, busy, no permission):
                # nothing moved and nothing was measured, so no run file is left behind.
                if output is not None and not journal.anything_recorded():
                    journal.close()
                    remove_run_file(output)
                raise
    finally:
        backend.close()


def changed_files(run: Run, files: Files) -> list[str]:
    """Which of the run's files differ from those given now (by hash)."""
    stored = run.meta["hashes"]
    now = files.hashes()
    changed = [
        name
        for name, key in (("plan", "plan_sha256"), ("rig", "rig_sha256"), ("scene", "scene_sha256"))
        if stored.get(key) != now[key] and not (name == "scene" and now[key] is None)
    ]
    if run.meta.get("alignment_sha256") != now.get("alignment_sha256"):
        changed.append("alignment")
    return changed


def check_stored_texts(run: Run) -> None:
    """`JournalError` if a plan, rig or scene text the run file stores no longer has the
    SHA-256 the run recorded when it started: the journal was edited, and what it says was
    measured from can no longer be trusted."""
    recorded = run.meta.get("hashes", {})
    for name in ("plan", "rig", "scene"):
        text = run.meta.get(f"{name}_text")
        expected = recorded.get(f"{name}_sha256")
        if text is not None and expected and sha256(str(text).encode("utf-8")) != expected:
            raise JournalError(
                f"{run.path}: the stored {name} text does not match the sha256 the run "
                "recorded: the run file was edited; it cannot be resumed"
            )


def current_files(run: Run, plan: Path | None, rig: Path | None, scene: Path | None) -> Files:
    """The files a run was made from as they are on disk now (paths from the journal
    unless given); a file that is gone keeps its stored text."""

    def now(given: Path | None, key: str) -> tuple[Path | None, bytes | None]:
        path = given or (Path(run.meta[f"{key}_path"]) if run.meta.get(f"{key}_path") else None)
        stored = run.meta.get(f"{key}_text")
        if path is not None and path.is_file():
            return path, read_bytes(path)
        if given is not None:
            raise ConfigError(f"--{key} {given}: no such file")
        return path, None if stored is None else str(stored).encode("utf-8")

    plan_path, plan_text = now(plan, "plan")
    rig_path, rig_text = now(rig, "rig")
    scene_path, scene_text = now(scene, "scene")
    assert plan_text is not None and rig_text is not None
    aligned = load(rig_path or Path("rig"), RigSpec, raw=rig_text).alignment
    alignment_text = None
    if aligned is not None:  # the file the rig file names now; gone: the stored text
        named = named_alignment(rig_path, aligned)
        stored = run.meta.get("alignment_text")
        alignment_text = (
            read_bytes(named)
            if named.is_file()
            else None
            if stored is None
            else str(stored).encode("utf-8")
        )
    return Files(plan_path, plan_text, rig_path, rig_text, scene_path, scene_text, alignment_text)


def resume(
    path: Path,
    *,
    plan_path: Path | None = None,
    rig_path: Path | None = None,
    scene_path: Path | None = None,
    force: bool = False,
    retry_skipped: bool = False,
    progress: Observer | None = None,
    argv: list[str] | None = None,
    max_page_count: int | None = None,
    speedup: float | None = None,
    on_ready: Callable[[], None] | None = None,
) -> SessionResult:
    """Measure what is missing from the run file at ``path`` (module docstring);
    ``on_ready``: called once every check has passed, before anything is written to the
    run or moves."""
    journal = Journal.reopen(path, durable=False, max_page_count=max_page_count)
    try:
        run = read_run(journal.conn, path)
        check_stored_texts(run)
        files = current_files(run, plan_path, rig_path, scene_path)
        changed = changed_files(run, files)
        if changed and not force:
            name = changed[0]
            where = files.plan_path if name == "plan" else files.rig_path
            where = files.scene_path if name == "scene" else where
            if name == "alignment":
                where = run.meta.get("alignment_path") or files.rig_path
            raise ConfigError(
                f"{where}: the {name} file changed since the run started (sha256 differs "
                f"from the journal's); restore it, or resume with --force to accept the change"
            )
        kind: BackendKind = run.meta["backend"]
        rig = run.plan.rig
        if changed:  # forced: the devices follow the rig file as it is now
            rig = Rig.from_yaml(files.rig_path or Path("rig"), files.rig_text, files.alignment_text)
        scene: Scene | None = None
        if backends.needs_scene(rig, kind):
            if files.scene_text is None:
                raise ConfigError(f"{path}: the run's scene is not stored; give --scene")
            scene = load_scene(files.scene_path or Path("scene"), rig, raw=files.scene_text)
        seed = run.meta.get("seed")
        started = float(run.meta["started_unix"])
        speed = speedup or float(run.meta.get("speedup") or 50.0)
        backend = backends.build(
            kind,
            rig,
            scene,
            seed,
            started,
            speedup=speed,
            any_detector=bool(run.meta.get("any_detector")),
        )
        try:
            hygiene.warn(preflight(run.plan, backend, files.plan_path, rig))
        except GonioError:
            backend.close()
            raise
        try:
            if on_ready is not None:
                on_ready()
            journal.upgrade()
            journal.make_durable(backend.durable)
            if changed:
                journal.start_session(utc_now(), {"forced": changed, "hashes": files.hashes()})
                journal.end_session(utc_now(), "forced")
            return _run_engine(
                journal,
                run.plan,
                backend,
                run,
                progress=progress or Unobserved(),
                retry_skipped=retry_skipped,
                argv=argv or [],
            )
        finally:
            backend.close()
    finally:
        journal.close()
