"""What a simulated run's stored scene file says that analysis needs, read without the
simulator through the scene file's own schema (`gonio.scene`): the material it measured,
the band its detector saw it in and the rig's true misalignment (the truth a measurement
is compared with), and the effects its simulation modelled.

Each reader validates only the section it reads, with the model `Scene` declares for it
(the material a `MaterialSpec`, the band `DetectorSpec.band`, the effects an
`EffectsSpec`): the band of a run needs nothing of its material, whose tabulated file
may be slow to load or gone. A stored text may have been edited: a mistake in what is
read is one `ConfigError` line, never a hang or a traceback."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import TypeAdapter, ValidationError

from gonio.brdf import MaterialSpec
from gonio.config import ConfigError, dotted, located, read_yaml
from gonio.errors import GonioError
from gonio.radiometry import band_eval
from gonio.rig import Alignment
from gonio.scene import Band, DetectorSpec, EffectsSpec
from gonio.types import BrdfEval

_BAND: TypeAdapter[Band] = TypeAdapter(Band)


def _where(scene_path: str | None) -> str:
    return f"{scene_path or 'scene'} (as stored in the run)"


def _data(scene_text: str, scene_path: str | None = None) -> dict[str, Any]:
    """The stored scene's YAML, read within the bounds of a configuration file."""
    data, _ = read_yaml(Path(_where(scene_path)), scene_text.encode("utf-8", "surrogatepass"))
    return data if isinstance(data, dict) else {}


def _refused(section: str, exc: ValidationError, scene_path: str | None = None) -> ConfigError:
    """The first problem of a section's validation, one line: where, field, what."""
    loc, message = located(exc.errors(include_url=False)[0])
    return ConfigError(f"{_where(scene_path)}: {dotted((section, *loc))}: {message}")


def _effects(data: dict[str, Any]) -> EffectsSpec:
    """The scene's effects, as `EffectsSpec` reads them (none given: none)."""
    given = data.get("effects")
    try:
        return EffectsSpec.model_validate({} if given is None else given)
    except ValidationError as exc:
        raise _refused("effects", exc) from None


def _band(data: dict[str, Any]) -> Band:
    """The band of the scene's detector, as `DetectorSpec.band` reads it."""
    detector = data.get("detector")
    if not isinstance(detector, dict) or detector.get("band") is None:
        default: Band = DetectorSpec.model_fields["band"].default
        return default
    try:
        return _BAND.validate_python(detector["band"])
    except ValidationError as exc:
        raise _refused("detector.band", exc) from None


def scene_alignment(scene_text: str, axes: Sequence[str]) -> Alignment | None:
    """The rig's true misalignment the scene's ``misalignment`` effect gives, for a rig
    with ``axes`` (None: the rig is as its file says); `ConfigError` if it is not one."""
    spec = _effects(_data(scene_text)).misalignment
    if spec is None:
        return None
    try:
        return spec.alignment(axes)
    except ValueError as exc:
        raise ConfigError(f"{_where(None)}: effects.misalignment: {exc}") from None


def scene_band(scene_text: str) -> Band:
    """The band of the scene's simulated detector ("luminance" unless it names one)."""
    return _band(_data(scene_text))


def scene_effects(scene_text: str) -> frozenset[str]:
    """The names of the effects the scene's simulation models (a list or a mapping)."""
    return frozenset(_effects(_data(scene_text)).names())


def scene_truth(scene_text: str, scene_path: str | None, band: str | None = None) -> BrdfEval:
    """f(ωi, ωo) (sr⁻¹) of the scene's ``material:`` (a relative ``path`` resolves against
    ``scene_path``) as ``band`` sees it (None: the scene detector's band; ``rgb``: the
    three channels, (..., 3)); `GonioError` if the stored scene has no material."""
    data = _data(scene_text, scene_path)
    if data.get("material") is None:
        raise GonioError(f"{scene_path or 'scene'}: the stored scene has no material")
    try:
        spec = MaterialSpec.model_validate(
            data["material"], context={"path": scene_path or "scene"}
        )
    except ValidationError as exc:
        raise _refused("material", exc, scene_path) from None
    model = spec.model()
    band = _band(data) if band is None else band
    if band == "rgb":
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    return band_eval(model, band)
