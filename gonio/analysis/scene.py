"""What a simulated run's stored scene file says that analysis needs, read without the
simulator: the material it measured and the band its detector saw it in (the truth a
measurement is compared with)."""

from __future__ import annotations

from typing import Any

import numpy as np
import yaml

from gonio.brdf.base import BRDF
from gonio.brdf.material import MaterialSpec
from gonio.errors import GonioError
from gonio.radiometry.bands import band_eval
from gonio.types import BrdfEval


def _data(scene_text: str) -> dict[str, Any]:
    data = yaml.safe_load(scene_text)
    return data if isinstance(data, dict) else {}


def scene_band(scene_text: str) -> str:
    """The band of the scene's simulated detector ("luminance" unless it names one)."""
    detector = _data(scene_text).get("detector")
    band = detector.get("band") if isinstance(detector, dict) else None
    return str(band) if band else "luminance"


def scene_material(scene_text: str, scene_path: str | None) -> BRDF:
    """The scene's ``material:`` as a model (a relative ``path`` resolves against
    ``scene_path``); `GonioError` if the stored scene has none."""
    material = _data(scene_text).get("material")
    if material is None:
        raise GonioError(f"{scene_path or 'scene'}: the stored scene has no material")
    spec = MaterialSpec.model_validate(material, context={"path": scene_path or "scene"})
    return spec.model()


def scene_truth(scene_text: str, scene_path: str | None, band: str) -> BrdfEval:
    """f(ωi, ωo) (sr⁻¹) of the scene's material as ``band`` sees it; for ``rgb``, the
    three channels (..., 3)."""
    model = scene_material(scene_text, scene_path)
    if band == "rgb":
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    return band_eval(model, band)
