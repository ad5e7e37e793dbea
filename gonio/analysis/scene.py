"""What a simulated run's stored scene file says that analysis needs, read without the
simulator: the material it measured, the band its detector saw it in and the rig's
true misalignment (the truth a measurement is compared with), and the effects its
simulation modelled."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from gonio.brdf.material import MaterialSpec
from gonio.config import ConfigError, describe, read_yaml
from gonio.errors import GonioError
from gonio.radiometry.bands import band_eval
from gonio.rig import Alignment, AlignmentSpec
from gonio.types import BrdfEval


def _data(scene_text: str, scene_path: str | None = None) -> dict[str, Any]:
    """The stored scene's YAML, read within the bounds of a configuration file (a stored
    text may have been edited: `ConfigError`, one line, not a hang or a traceback)."""
    where = Path(f"{scene_path or 'scene'} (as stored in the run)")
    data, _ = read_yaml(where, scene_text.encode("utf-8", "surrogatepass"))
    return data if isinstance(data, dict) else {}


def _band(data: dict[str, Any]) -> str:
    detector = data.get("detector")
    band = detector.get("band") if isinstance(detector, dict) else None
    return str(band) if band else "luminance"


def scene_alignment(scene_text: str, axes: Sequence[str]) -> Alignment | None:
    """The rig's true misalignment the scene's ``misalignment`` effect gives, for a rig
    with ``axes`` (None: the rig is as its file says); `ConfigError` if it is not one."""
    effects = _data(scene_text).get("effects")
    if not isinstance(effects, dict) or "misalignment" not in effects:
        return None
    try:
        spec = AlignmentSpec.model_validate(effects["misalignment"] or {})
        return spec.alignment(axes)
    except (ValidationError, ValueError) as exc:
        raise ConfigError(f"scene (as stored in the run): effects.misalignment: {exc}") from None


def scene_band(scene_text: str) -> str:
    """The band of the scene's simulated detector ("luminance" unless it names one)."""
    return _band(_data(scene_text))


def scene_effects(scene_text: str) -> frozenset[str]:
    """The names of the effects the scene's simulation models (a list or a mapping)."""
    effects = _data(scene_text).get("effects")
    if isinstance(effects, dict | list):
        return frozenset(str(name) for name in effects)
    return frozenset()


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
        first = exc.errors(include_url=False)[0]
        raise ConfigError(
            f"{scene_path or 'scene'} (as stored in the run): material.{describe(first)}"
        ) from None
    model = spec.model()
    band = _band(data) if band is None else band
    if band == "rgb":
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    return band_eval(model, band)
