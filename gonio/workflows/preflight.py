"""What is checked before a run creates or moves anything: the files it is made from
(`Files`), the backend the rig chooses and the scene it needs (`check_scene`), the run
file to create (`check_output`), a fly plan's backend (`refuse_fly_spec`, before
planning, with the stream
check of a hardware detector, `gonio.workflows.stream_check`) and the backend's
devices (`preflight`, with the bus hygiene findings of `gonio.workflows.hygiene`).
`dry_run` checks all of it, and that the devices answer, without moving.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drivers.base import dark_subtracted, reading_unit
from gonio.acquire import geometry_label, reference_pose
from gonio.config import ConfigError
from gonio.errors import GonioError
from gonio.output import refuse_inputs
from gonio.planner import Plan, PlanSpec, content_hash, sha256
from gonio.rig import Rig, SerialInterfaceSpec
from gonio.scene import Scene
from gonio.workflows import backends, hygiene, stream_check
from gonio.workflows.backends import BackendKind

#: Journal bytes per sample, measured on the shipped plans (with a simulated
#: snapshot), for the disk-space check of a dry run; doubled there for the WAL.
BYTES_PER_SAMPLE = 700


@dataclass(frozen=True)
class Files:
    """The files a run is made from: paths (None: made in code) and bytes."""

    plan_path: Path | None
    plan_text: bytes
    rig_path: Path | None
    rig_text: bytes
    scene_path: Path | None = None
    scene_text: bytes | None = None
    #: The alignment file the rig file names (None: it names none).
    alignment_text: bytes | None = None

    def hashes(self) -> dict[str, str | None]:
        """Each file's sha256 (the alignment's only where the rig names one) and their
        `content_hash`."""
        out = {
            "plan_sha256": sha256(self.plan_text),
            "rig_sha256": sha256(self.rig_text),
            "scene_sha256": None if self.scene_text is None else sha256(self.scene_text),
            "content": content_hash(
                self.plan_text, self.rig_text, self.scene_text, self.alignment_text
            ),
        }
        if self.alignment_text is not None:
            out["alignment_sha256"] = sha256(self.alignment_text)
        return out


def check_scene(
    files: Files,
    rig: Rig,
    scene: Scene | None,
    *,
    rehearse: bool = False,
    force_simulated: bool = False,
) -> BackendKind:
    """The backend the rig file chooses (``force_simulated``: the simulated one whatever
    its bus); `ConfigError` if that backend needs a scene and none is given (a command
    checks it before planning, so the refusal is its only line)."""
    kind: BackendKind = "simulated" if force_simulated else backends.kind_of(rig, rehearse)
    if backends.needs_scene(rig, kind) and scene is None:
        why = "the detector is simulated"
        if kind == "rehearsal":
            why = "--rehearse simulates what the detector sees"
        raise ConfigError(f"{files.rig_path or 'rig'}: {why}: give --scene")
    return kind


def check_output(path: Path | None, overwrite: bool, inputs: Files | None = None) -> None:
    """`ConfigError` unless a run file can be created at ``path`` (checked by creating
    and removing a file beside it, not only by permission bits) and is none of the run's
    ``inputs``."""
    if path is None:
        return
    if inputs is not None:
        refuse_inputs(path, "-o", (inputs.plan_path, inputs.rig_path, inputs.scene_path))
    if path.is_dir():
        raise ConfigError(f"-o {path}: is a folder; expected a run file name")
    if (path.exists() or path.is_symlink()) and not overwrite:
        raise ConfigError(
            f"-o {path}: a run file already exists; give another name, continue it with "
            "--resume, or replace it with --overwrite"
        )
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ConfigError(f"-o {path}: the folder {folder} does not exist")
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=f".{path.name}.", suffix=".probe"):
            pass
    except OSError as exc:
        raise ConfigError(f"-o {path}: cannot write in {folder}: {exc.strerror or exc}") from None


def refuse_fly(plan: Plan, kind: str, scene: Scene | None = None) -> None:
    """`refuse_fly_spec` of a plan already made (a stored plan, resumed)."""
    if plan.is_fly:
        refuse_fly_spec(plan.spec, plan.rig, kind, scene)


def refuse_fly_spec(
    spec: PlanSpec, rig: Rig, kind: str, scene: Scene | None = None, scene_path: Path | None = None
) -> None:
    """`ConfigError` for a fly plan on a backend that cannot acquire it, before it is
    planned: a simulated detector of a lock-in ``scene`` (it cannot stream), hardware
    whose serial detector has no passing stream check for its configuration and the
    plan's rate (`gonio.workflows.stream_check.fly_refusal`), or a rehearsal or hardware
    whose detector cannot stream at all (`refuse_fly_detector`)."""
    if spec.sampling.strategy != "fly":
        return
    if scene is not None and kind != "hardware" and not scene.detector.streams:
        raise ConfigError(
            f"{scene_path or 'scene'}: detector.kind: plan {spec.name!r} is a fly plan and the "
            f"simulated {scene.detector.kind} detector cannot stream; expected kind: adc, or a "
            "stop-and-go plan"
        )
    if kind == "simulated":
        return
    interface = rig.spec.detector.interface
    if kind == "hardware":
        if isinstance(interface, SerialInterfaceSpec) and interface.stream is not None:
            fly = spec.sampling.fly
            why = stream_check.fly_refusal(rig, None if fly is None else fly.rate_hz)
            if why is None:
                return
            raise ConfigError(f"plan {spec.name!r} is a fly plan: {why}")
        raise ConfigError(
            f"plan {spec.name!r}: fly plans are acquired on the simulated and rehearsal "
            "backends only, and on hardware whose serial detector passed `gonio detector "
            "check-stream` (this run's detector is not one); use `gonio simulate`, `gonio "
            "acquire --rehearse`, or a stop-and-go plan"
        )
    refuse_fly_detector(spec, rig)


def refuse_fly_detector(spec: PlanSpec, rig: Rig) -> None:
    """`ConfigError` for a fly plan on a rig whose detector cannot stream at all (a
    PyMeasure instrument, a serial detector without a ``stream`` section)."""
    interface = rig.spec.detector.interface
    if spec.sampling.strategy == "fly" and (
        interface.kind == "pymeasure"
        or (isinstance(interface, SerialInterfaceSpec) and interface.stream is None)
    ):
        raise ConfigError(
            f"{rig.source or 'rig'}: detector.interface: plan {spec.name!r} is a fly plan and "
            f"this {interface.kind} detector cannot stream; expected a serial detector with a "
            "stream section, or kind: simulated"
        )


def preflight(
    plan: Plan,
    backend: backends.Backend,
    plan_path: Path | None,
    rig: Rig | None = None,
    *,
    dry: bool = False,
) -> list[hygiene.Finding]:
    """Refuse, before anything is created or moved, a run the backend cannot finish;
    the findings of the bus hygiene checks (`gonio.workflows.hygiene`) on the devices of
    ``rig`` (default the plan's), whose warnings the caller shows. ``dry``: for a dry
    run, which asks no operator (`needs_operator` is the caller's to report)."""
    reference_pose(plan.rig)  # a reference reading the calibration could not trust
    spec = plan.spec.acquisition.calibration
    # A detector whose readings are dark-subtracted (a lock-in) takes no dark reading.
    subtracted = dark_subtracted(backend.devices.detector)
    if spec.dark and backend.devices.light is None and not subtracted:
        raise ConfigError(
            f"{plan_path or 'plan'}: acquisition.calibration.dark: the rig's light cannot be "
            "switched (light.switch: none), so no dark reading can be taken; give the rig a "
            "switch, or set dark: false (the dark signal is then taken as 0 counts)"
        )
    if needs_operator(backend) and not dry:
        raise GonioError(
            "the reference standard is put on the stage by the operator and no one can be "
            "asked (no terminal): run gonio acquire from a terminal"
        )
    return hygiene.backend_findings(rig or plan.rig, backend)


def needs_operator(backend: backends.Backend) -> bool:
    """Whether the run asks an operator to swap the sample and the reference standard
    and no one can be asked here (no terminal)."""
    stage = backend.stage
    return isinstance(stage, backends.OperatorStage) and not stage.can_ask()


def dry_run(
    plan: Plan,
    files: Files,
    *,
    scene: Scene | None,
    output: Path | None,
    overwrite: bool,
    rehearse: bool = False,
) -> list[str]:
    """Check what a run needs without moving anything; the lines to print (raises a
    `GonioError` at the first problem)."""
    rig = plan.rig
    kind = check_scene(files, rig, scene, rehearse=rehearse)
    refuse_fly(plan, kind)
    lines = [f"backend {kind}: rig {rig.spec.name!r} ({files.rig_path or 'in code'})"]
    lo, hi = rig.limits[:, 0], rig.limits[:, 1]
    outside = ~np.all((plan.angles >= lo) & (plan.angles <= hi), axis=1)
    if outside.any():
        raise GonioError(
            f"{int(outside.sum())} targets lie outside the axis limits (first: target "
            f"{int(np.flatnonzero(outside)[0])}); re-plan with this rig"
        )
    lines.append(f"targets: {len(plan)} within the axis limits")
    reference_pose(rig)
    lines.append(
        f"reference standard: read at {geometry_label(rig)} on "
        f"{rig.reference_diameter_mm:g} mm, unclipped"
    )
    check_output(output, overwrite, files)
    if output is not None:
        folder = output.parent if str(output.parent) else Path(".")
        need = 2 * BYTES_PER_SAMPLE * len(plan) + (1 << 20)
        free = shutil.disk_usage(folder).free
        if free < need:
            raise GonioError(
                f"-o {output}: {free / 1e6:.1f} MB free in {folder}; the run needs about "
                f"{need / 1e6:.1f} MB"
            )
        lines.append(
            f"output: {output} writable, {free / 1e9:.1f} GB free (needs {need / 1e6:.1f} MB)"
        )
    backend = backends.build(kind, rig, scene, None if scene is None else scene.seed, time.time())
    try:
        # what a run refuses, its dry run refuses
        findings = preflight(plan, backend, files.plan_path, dry=True)
        lines += [str(f) for f in findings]
        if needs_operator(backend):  # a dry run asks nothing; the run will
            lines.append(
                "operator: the run will ask for the reference standard to be put on the "
                "stage (no terminal here): run it from a terminal"
            )
        with backend.devices as devices:
            positions = devices.bus.positions()
            health = devices.bus.health()
            reading = devices.detector.measure(devices.detector.exposure_range_s[0], 1)
        lines.append(
            f"motors: {len(positions)} axes answer, "
            f"{max(h.temperature_c for h in health.values()):g} °C at most"
        )
        unit = reading_unit(devices.detector)
        lines.append(f"detector: answers ({reading.value:g} {unit} at its shortest exposure)")
    finally:
        backend.close()
    return lines
