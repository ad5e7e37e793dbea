"""What a simulated run's stored scene file says that analysis needs, read without the
simulator: the material it measured and the band its detector saw it in (the truth a
measurement is compared with)."""

from __future__ import annotations

from typing import Any

import numpy as np
import yaml

from gonio.brdf.material import MaterialSpec
from gonio.errors import GonioError
from gonio.radiometry.bands import band_eval
from gonio.types import BrdfEval


def _data(scene_text: str) -> dict[str, Any]:
    data = yaml.safe_load(scene_text)
    return data if isinstance(data, dict) else {}


def _band(data: dict[str, Any]) -> str:
    detector = data.get("detector")
    band = detector.get("band") if isinstance(detector, dict) else None
    return str(band) if band else "luminance"


def scene_band(scene_text: str) -> str:
    """The band of the scene's simulated detector ("luminance" unless it names one)."""
    return _band(_data(scene_text))


def scene_truth(scene_text: str, scene_path: str | None, band: str | None = None) -> BrdfEval:
    """f(ωi, ωo) (sr⁻¹) of the scene's ``material:`` (a relative ``path`` resolves against
    ``scene_path``) as ``band`` sees it (None: the scene detector's band; ``rgb``: the
    three channels, (..., 3)); `GonioError` if the stored scene has no material."""
    data = _data(scene_text)
    if data.get("material") is None:
        raise GonioError(f"{scene_path or 'scene'}: the stored scene has no material")
    spec = MaterialSpec.model_validate(data["material"], context={"path": scene_path or "scene"})
    model = spec.model()
    band = _band(data) if band is None else band
    if band == "rgb":
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    return band_eval(model, band)
