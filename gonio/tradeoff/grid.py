"""A sweep file read with its rig and scenes, and its combinations: one `Task` each,
named by a stable id (a hash of everything that determines its result) from which its
seeds are drawn, and carrying every byte a worker needs (no file is read on a worker).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from gonio.config import (
    ConfigError,
    describe,
    dotted,
    excerpt,
    line_of,
    load,
    read_bytes,
    read_yaml,
    spec_text,
)
from gonio.planner import FlySpec, PlanSpec, Warp, blur_floor_deg
from gonio.rig import Rig, RigSpec
from gonio.scene import EffectsSpec, load_scene
from gonio.tradeoff.spec import (
    AXIS_NAMES,
    FLY,
    FLY_AXES,
    NONE,
    SCENE,
    STOP,
    STOP_AXES,
    WARPED,
    Effects,
    SweepSpec,
    Without,
    effects_label,
)

#: The most combinations one sweep may hold (a few seconds each: weeks of CPU).
MAX_COMBINATIONS = 100_000
#: Framing of a combination's id (the version names the framing, not gonio's).
_ID_MAGIC = "gonio tradeoff combination v1"
#: The first guess of the target under a time budget (stop-and-go, fly readings).
STOP_PILOT, FLY_PILOT = 500, 5000
#: The input columns of a results row, in order (the figures follow: `runner`).
INPUT_COLUMNS = ("id", "scene", *AXIS_NAMES, "replicate", "plan_seed", "run_seed")


@dataclass(frozen=True)
class SceneFile:
    """A scene file of the sweep: its name (the scene's ``name``), path and bytes."""

    name: str
    path: Path
    text: bytes
    effects: dict[str, Any]  # the scene's own, as listed in the file (with parameters)


@dataclass(frozen=True)
class Task:
    """One combination, ready to run anywhere: its results-row inputs, the plan it asks
    for, the scene (bytes and the effects to model), the rig (bytes, scaled) and how it
    is scored."""

    id: str
    inputs: dict[str, Any]  # `INPUT_COLUMNS` → value
    plan: dict[str, Any]  # a `PlanSpec`'s fields (no rig: the rig comes with the task)
    scene_path: str
    scene_text: bytes
    effects: dict[str, Any]
    rig_path: str
    rig_text: bytes
    run_seed: int
    method: str
    test_pairs: int
    test_seed: int
    budget_s: float | None = None  # instrument time the plan's target is fitted to (s)
    extrapolate: str | None = None  # how the reconstruction fills unsupported pairs
    only_supported: bool = False  # score only the pairs inside the support

    def plan_spec(self) -> PlanSpec:
        return PlanSpec.model_validate(self.plan)


@dataclass(frozen=True)
class Sweep:
    """A sweep file as read: the spec, the rig, the scenes and every combination's task
    (scenes outermost, then the axes in the file's order, replicates innermost)."""

    path: Path
    spec: SweepSpec
    rig: Rig
    scenes: tuple[SceneFile, ...]
    tasks: tuple[Task, ...]

    def task(self, id_: str) -> Task:
        return next(t for t in self.tasks if t.id == id_)


def load_sweep(path: str | Path) -> Sweep:
    """Read and check a sweep file, its rig and scenes (`ConfigError`, one line, on any
    mistake), and lay out its combinations."""
    path = Path(path)
    raw = read_bytes(path)
    spec = load(path, SweepSpec, raw=raw)
    node = read_yaml(path, raw)[1]

    def refuse(loc: Sequence[int | str], message: str) -> ConfigError:
        line = line_of(node, loc)
        return ConfigError(f"{path}{'' if line is None else f':{line}'}: {dotted(loc)}: {message}")

    # Counted from the lists as written, before a rig is scaled or a scene read: a sweep
    # of a billion combinations is one line at once, whatever else it asks for.
    size = len(spec.scenes) * spec.replicates
    for name in AXIS_NAMES:
        size *= len(getattr(spec.axes, name))
    if size > MAX_COMBINATIONS:
        raise refuse(
            ("axes",), f"{size:,} combinations; expected at most {MAX_COMBINATIONS:,} in one sweep"
        )
    rig_path = _named_file(path, spec.rig, ("rig",), refuse)
    rig = Rig.from_yaml(rig_path)
    _check_detector(spec, rig, refuse)
    _check_fly(spec, rig, refuse)
    _check_minutes(spec, rig, refuse)
    rigs = {}
    for k, scale in enumerate(spec.axes.velocity_scale):
        try:
            rigs[scale] = scaled_rig(rig, scale)
        except ConfigError as exc:
            raise refuse(
                ("axes", "velocity_scale", k), f"the scaled rig is refused: {exc}"
            ) from None
    scenes = _scenes(spec, path, rig, refuse)
    _check_effects(spec, scenes, refuse)
    tasks = []
    for scene in scenes:
        seen: set[str] = set()
        for values in itertools.product(*(getattr(spec.axes, n) for n in AXIS_NAMES)):
            combination = applicable(dict(zip(AXIS_NAMES, values, strict=True)))
            key = json.dumps({n: _label(v) for n, v in combination.items()})
            if key in seen or spec.excluded(combination):
                continue
            seen.add(key)
            if combination["sampling"] == WARPED and not spec.warps_of(
                combination["parametrization"]
            ):
                raise refuse(
                    ("warps", combination["parametrization"]),
                    f"warped sampling in {combination['parametrization']} needs a warp (there "
                    "is no default for it); give one, or exclude {parametrization: "
                    f"{combination['parametrization']}, sampling: {WARPED}}}",
                )
            if combination["minutes"] is not None and combination["sampling"] == "adaptive":
                raise refuse(
                    ("axes", "minutes"),
                    "adaptive sampling plans its second pass after the survey, so its target "
                    "cannot be fitted to a time budget; exclude {sampling: adaptive, minutes: "
                    f"{combination['minutes']:g}}} or give minutes: [null]",
                )
            for replicate in range(spec.replicates):
                tasks.append(_task(spec, scene, rigs, rig_path, combination, replicate))
    if not tasks:
        raise refuse(("exclude",), "every combination is excluded; expected some to run")
    return Sweep(path, spec, rig, scenes, tuple(tasks))


def applicable(combination: dict[str, Any]) -> dict[str, Any]:
    """``combination`` with None for the axes that do not apply to it: the fly axes of
    a stop-and-go one, the stop-and-go axes of a fly one, ``samples`` under a time
    budget (``minutes``). Combinations that differ only there are one."""
    out = dict(combination)
    unused = list(STOP_AXES if out["motion"] == FLY else FLY_AXES)
    if out["minutes"] is not None:
        unused.append("samples")
    out.update(dict.fromkeys(unused))
    return out


def _label(value: Any) -> str:
    return effects_label(value) if isinstance(value, list | Without) else str(value)


def _named_file(sweep: Path, name: str, loc: tuple[str | int, ...], refuse: Any) -> Path:
    """The file a sweep names at ``loc``, relative to the sweep file's folder (``..``
    resolved in the name, as a shell would); refused if it is a folder or its name is
    too long to look up (reading it says what else is wrong)."""
    path = Path(os.path.normpath(sweep.parent / name))
    try:
        folder = path.is_dir()
    except OSError as exc:
        raise refuse(loc, f"{excerpt(name)}: {exc.strerror or exc}") from None
    if folder:
        raise refuse(loc, f"{path} is a folder; expected a file")
    return path


def scaled_rig(rig: Rig, scale: float) -> bytes:
    """The rig file's bytes with every axis's max velocity × ``scale`` and max
    acceleration × ``scale``² (the same trapezoidal profiles, run ``scale`` times as
    fast: each move takes 1/``scale`` of the time); the file itself for 1."""
    if scale == 1.0:
        return rig.text
    data = rig.spec.model_dump(mode="json")
    for axis in data["axes"].values():
        axis["max_velocity_deg_s"] *= scale
        axis["max_acceleration_deg_s2"] *= scale * scale
    try:
        spec = RigSpec.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(describe(exc.errors(include_url=False)[0])) from None
    Rig(spec)  # the checks of a rig file (motor limits)
    return spec_text(spec)


def _check_detector(spec: SweepSpec, rig: Rig, refuse: Any) -> None:
    detector = rig.spec.detector
    lo, hi = detector.exposure_range_s
    if STOP not in spec.axes.motion:
        return  # no stop-and-go combination: exposures and averages do not apply
    for k, seconds in enumerate(spec.axes.exposure_s):
        if not lo <= seconds <= hi:
            raise refuse(
                ("axes", "exposure_s", k),
                f"{seconds:g} s is outside the detector's exposure range [{lo:g}, {hi:g}] s "
                f"(detector.exposure_range_s of {rig.source})",
            )
    for k, averages in enumerate(spec.axes.averages):
        if detector.max_averages is not None and averages > detector.max_averages:
            raise refuse(
                ("axes", "averages", k),
                f"{averages} averages; the detector takes at most {detector.max_averages} "
                f"(detector.max_averages of {rig.source})",
            )


def _check_fly(spec: SweepSpec, rig: Rig, refuse: Any) -> None:
    """Refuse a blur budget below the rig's floor for a segment swept (the encoders'
    quantization, `gonio.planner.fly.limits.blur_floor_deg`)."""
    if FLY not in spec.axes.motion:
        return
    for segment in spec.axes.segment:
        floor, axis = blur_floor_deg(rig, FlySpec(segment=segment))
        for k, blur in enumerate(spec.axes.blur_deg):
            if blur < floor:
                raise refuse(
                    ("axes", "blur_deg", k),
                    f"expected at least {floor:.3g}° for {segment} (the quantization of "
                    f"{axis}'s encoder, one tick / √12, in {rig.source}), got {blur:g}",
                )


def sample_s(spec: SweepSpec, rig: Rig) -> float:
    """The shortest time one sample of the sweep's combinations takes (s): the rig's
    settle, then the shortest exposure × averages (stop-and-go) or integration (fly,
    1 / rate_hz)."""
    reads = []
    if STOP in spec.axes.motion:
        reads.append(min(spec.axes.exposure_s) * min(spec.axes.averages))
    if FLY in spec.axes.motion:
        reads.append(1.0 / max(spec.axes.rate_hz))
    return rig.spec.settle_s + min(reads)


def _check_minutes(spec: SweepSpec, rig: Rig, refuse: Any) -> None:
    """Refuse a time budget shorter than one sample (`sample_s`): no plan fits it."""
    least = sample_s(spec, rig)
    for k, minutes in enumerate(spec.axes.minutes):
        if minutes is not None and 60.0 * minutes < least:
            raise refuse(
                ("axes", "minutes", k),
                f"expected at least {least / 60.0:.3g} min, the time of one sample on this "
                f"rig ({least:.3g} s: its settle_s and the shortest exposure), got {minutes:g}",
            )


def _scenes(spec: SweepSpec, path: Path, rig: Rig, refuse: Any) -> tuple[SceneFile, ...]:
    out: list[SceneFile] = []
    for k, name in enumerate(spec.scenes):
        scene_path = _named_file(path, name, ("scenes", k), refuse)
        text = read_bytes(scene_path)
        scene = load_scene(scene_path, rig, raw=text)
        if FLY in spec.axes.motion and not scene.detector.streams:
            raise refuse(
                ("scenes", k),
                f"{scene_path}: detector.kind: the simulated {scene.detector.kind} detector "
                "cannot stream, and the sweep has fly combinations (axes.motion); expected "
                "kind: adc, or motion: [stop]",
            )
        if any(s.name == scene.name for s in out):
            raise refuse(
                ("scenes", k), f"another scene of the sweep is named {excerpt(scene.name)}"
            )
        effects = scene.effects.model_dump(mode="json")
        out.append(SceneFile(scene.name, scene_path, text, effects))
    return tuple(out)


def _check_effects(spec: SweepSpec, scenes: tuple[SceneFile, ...], refuse: Any) -> None:
    """Refuse an effects value a scene cannot model (an effect named without the
    parameters it needs, which the scene does not list either), before anything runs."""
    for k, effects in enumerate(spec.axes.effects):
        for scene in scenes:
            try:
                EffectsSpec.model_validate(resolved_effects(effects, scene))
            except ValidationError as exc:
                first = exc.errors()[0]
                where = ".".join(str(part) for part in first["loc"])
                raise refuse(
                    ("axes", "effects", k),
                    f"{where}: {first['msg'].lower()} (scene {excerpt(scene.name)} does not "
                    "list the effect; expected its parameters in the scene file)",
                ) from None


def resolved_effects(effects: Effects, scene: SceneFile) -> dict[str, Any]:
    """The effects a combination models: the scene's own (``scene``), none, only those
    named (with the scene's parameters where it lists them, else the defaults), or the
    scene's less those named."""
    if effects == SCENE:
        return dict(scene.effects)
    if effects == NONE:
        return {}
    if isinstance(effects, Without):
        return {k: v for k, v in scene.effects.items() if k not in effects.without}
    assert isinstance(effects, list)
    return {name: scene.effects.get(name, {}) for name in effects}


def sampling_fields(
    combination: dict[str, Any],
    *,
    target: int,
    seed: int,
    warps: dict[str, Warp],
    adaptive: dict[str, Any],
) -> dict[str, Any]:
    """The ``sampling`` field of a combination's plan: ``target`` and ``seed``; a fly
    combination's ``segment``, ``rate_hz`` and ``blur_deg``, or a stop-and-go one's
    strategy (``warped``: Sobol with ``warps``) and the adaptive options (``adaptive``:
    ``{"adaptive": …}`` or empty)."""
    strategy = combination["sampling"]
    fly = combination["motion"] == FLY
    sampling: dict[str, Any] = {
        "strategy": FLY if fly else "sobol" if strategy == WARPED else strategy,
        "target": target,
        "seed": seed,
    }
    if fly:
        sampling["fly"] = {k: combination[k] for k in ("segment", "rate_hz", "blur_deg")}
    else:
        sampling |= {"warps": {c: {"power": w.power} for c, w in warps.items()}, **adaptive}
    return sampling


def _task(
    spec: SweepSpec,
    scene: SceneFile,
    rigs: dict[float, bytes],
    rig_path: Path,
    combination: dict[str, Any],
    replicate: int,
) -> Task:
    parametrization, strategy = combination["parametrization"], combination["sampling"]
    effects = resolved_effects(combination["effects"], scene)
    warps = spec.warps_of(parametrization) if strategy == WARPED else {}
    options = spec.adaptive.model_dump(mode="json")
    adaptive = {"adaptive": options} if strategy == "adaptive" else {}
    rig_text = rigs[combination["velocity_scale"]]
    # The axes a sweep of stop-and-go plans without a time budget leaves at their
    # defaults are left out of the id: such a combination keeps its id of before they
    # existed.
    new_axes = {"motion": STOP, "minutes": None, **dict.fromkeys(FLY_AXES)}
    identity = {
        "magic": _ID_MAGIC,
        "seed": spec.seed,
        "scene_sha256": hashlib.sha256(scene.text).hexdigest(),
        "rig_sha256": hashlib.sha256(rig_text).hexdigest(),
        "isotropic": spec.isotropic,
        **{
            n: v
            for n, v in combination.items()
            if n != "effects" and not (n in new_axes and v == new_axes[n])
        },
        "effects": effects,
        "effects_label": effects_label(combination["effects"]),
        "warps": {c: w.power for c, w in warps.items()},
        **adaptive,
        "plan": spec.plan.model_dump(mode="json"),
        "evaluation": evaluation_identity(spec),
        "replicate": replicate,
    }
    digest = hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()
    id_ = digest[:16]
    plan_seed, run_seed = int(digest[16:24], 16), int(digest[24:32], 16)
    # Under a time budget the runner fits the target (`gonio.tradeoff.runner`); the
    # plan carries its first guess.
    target = combination["samples"] or (FLY_PILOT if combination["motion"] == FLY else STOP_PILOT)
    fly = combination["motion"] == FLY
    sampling = sampling_fields(
        combination, target=target, seed=plan_seed, warps=warps, adaptive=adaptive
    )
    plan: dict[str, Any] = {
        "name": f"{spec.name}-{id_}",
        "parametrization": parametrization,
        "isotropic": spec.isotropic,
        "sampling": sampling,
    }
    if not fly:
        plan["exposure"] = {
            "seconds": combination["exposure_s"],
            "averages": combination["averages"],
        }
    plan |= spec.plan.model_dump(mode="json")
    inputs = {
        "id": id_,
        "scene": scene.name,
        **combination,
        "effects": effects_label(combination["effects"]),
        "replicate": replicate,
        "plan_seed": plan_seed,
        "run_seed": run_seed,
    }
    assert tuple(inputs) == INPUT_COLUMNS
    return Task(
        id=id_,
        inputs=inputs,
        plan=plan,
        scene_path=str(scene.path),
        scene_text=scene.text,
        effects=effects,
        rig_path=str(rig_path),
        rig_text=rig_text,
        run_seed=run_seed,
        method=combination["method"],
        test_pairs=spec.evaluation.pairs,
        test_seed=spec.evaluation.seed,
        budget_s=None if combination["minutes"] is None else 60.0 * combination["minutes"],
        extrapolate=None if spec.evaluation.only_supported else spec.evaluation.extrapolate,
        only_supported=spec.evaluation.only_supported,
    )


def evaluation_identity(spec: SweepSpec) -> dict[str, Any]:
    """What of the evaluation settings enters a combination's id: the test set, and the
    fill when every pair is scored. Scoring the supported pairs only keeps the ids of the
    sweeps written before the fill existed (they scored those pairs)."""
    e = spec.evaluation
    fill = {} if e.only_supported else {"extrapolate": e.extrapolate}
    return {"pairs": e.pairs, "seed": e.seed, **fill}
