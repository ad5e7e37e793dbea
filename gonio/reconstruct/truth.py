"""What a reconstruction is compared with, from a one-word SPEC (docs/explanations/evaluation.md):

- ``scene`` (the default, None): the simulated run's scene material, as its band sees it;
- ``NAME`` or ``NAME:key=value,key=value``: the `gonio.brdf` model NAME with those
  parameters, each value read as YAML (``0.1``, ``conductor``, ``[0.18, 0.42, 1.37]``:
  commas inside brackets belong to the list), checked as a scene's material is;
- ``FILE.yaml`` / ``FILE.yml``: a material (``name:`` and its parameters) or a scene file
  (its ``material:``);
- any other existing file: another run, reconstructed by the ``reconstruct`` given.

A SPEC is read in that order: a name ending in .yaml or .yml is a material file, an
existing file a run, and anything else a model.

A model or material with RGB values is seen through a single-band run's band (luminance
weights, or the r, g or b channel), as the simulated detector sees it.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import yaml

from gonio.analysis import Measured
from gonio.brdf import BRDF, build
from gonio.errors import GonioError
from gonio.radiometry import band_eval
from gonio.types import BoolArray, BrdfEval, FloatArray

#: The default SPEC: the simulated run's own scene.
SCENE = "scene"
#: Commas that separate ``key=value`` items (not those inside a [list]).
_ITEM_SEPARATOR = re.compile(r",(?![^\[\]]*\])")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class Candidate(Protocol):
    """A reconstruction: values (N,) or (N, C) in sr⁻¹ for pairs (N, 3); NaN where it
    declines to answer. ``supported(wi, wo)`` (optional) says where it has data."""

    def eval(self, wi: FloatArray, wo: FloatArray) -> FloatArray: ...


#: Builds a reconstruction of a run's samples (for a truth that is another run).
Reconstructor = Callable[[Measured], Candidate]


@dataclass(frozen=True)
class Truth:
    """The reference f(ωi, ωo), what it is (``label``) and, for a reconstruction, where
    it is defined (``supported``; None: everywhere)."""

    label: str
    eval: BrdfEval
    supported: Callable[[FloatArray, FloatArray], BoolArray] | None = None


def truth_from_spec(
    spec: str | None, measured: Measured, *, reconstruct: Reconstructor | None = None
) -> Truth:
    """The truth SPEC names, for comparing with a reconstruction of ``measured`` (see
    the module docstring); `GonioError` (one line) for a SPEC that names nothing usable."""
    if spec is None or spec == SCENE:
        if measured.scene_text is None:
            raise GonioError(
                f"{measured.source}: a run on hardware has no scene to compare with; name a "
                "truth: a model NAME:key=value,…, a material YAML file or another run"
            )
        return Truth(f"the scene of {measured.source}", measured.scene_truth())
    path = Path(spec)
    if path.suffix.lower() in (".yaml", ".yml"):
        return Truth(f"the material of {spec}", _seen(_material_file(path), measured.band))
    if path.is_file():
        if reconstruct is None:
            raise GonioError(f"{spec}: a run as the truth needs a way to reconstruct it")
        other = reconstruct(Measured.from_run(spec))
        supported = getattr(other, "supported", None)
        return Truth(f"the reconstruction of {spec}", other.eval, supported)
    name, _, rest = spec.partition(":")
    if not _NAME.fullmatch(name.strip()):
        raise GonioError(
            f"{spec}: no such file, and not a model NAME:key=value,… (a truth is scene, a "
            "model, a material YAML file or a run file)"
        )
    try:
        model = build(name.strip(), _parameters(rest))
    except GonioError as exc:
        raise GonioError(f"truth {spec!r}: {exc}") from None
    return Truth(f"the model {spec}", _seen(model, measured.band))


def _parameters(text: str) -> dict[str, Any]:
    """``key=value,key=value`` → {key: YAML value}."""
    out: dict[str, Any] = {}
    for item in _ITEM_SEPARATOR.split(text) if text.strip() else []:
        key, eq, value = (part.strip() for part in item.partition("="))
        if not eq or not _NAME.fullmatch(key) or not value:
            raise GonioError(f"expected NAME:key=value,key=value; cannot read {item!r}")
        try:
            out[key] = yaml.safe_load(value)
        except yaml.YAMLError:
            raise GonioError(f"{key}: cannot read the value {value!r}") from None
    return out


def _material_file(path: Path) -> BRDF:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise GonioError(f"{path}: cannot read it ({exc.strerror})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f":{mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None)
        raise GonioError(
            f"{path}{where}: not valid YAML" + (f" ({problem})" if problem else "")
        ) from None
    if isinstance(data, dict) and isinstance(data.get("material"), dict):
        data = data["material"]
    if not isinstance(data, dict) or "name" not in data:
        raise GonioError(
            f"{path}: expected a material (name: MODEL and its parameters) or a scene "
            "with a material:"
        )
    params = data.get("params", {k: v for k, v in data.items() if k != "name"})
    if not isinstance(params, dict):
        raise GonioError(f"{path}: material.params: expected a mapping of parameters")
    try:
        return build(data["name"], params)
    except GonioError as exc:
        raise GonioError(f"{path}: material: {exc}") from None


def _seen(model: BRDF, band: str) -> BrdfEval:
    """f of ``model`` as a measurement in ``band`` sees it (RGB kept for an RGB one)."""
    if band == "rgb" or not model.is_rgb:
        return lambda wi, wo: np.asarray(model.eval(wi, wo), dtype=np.float64)
    return band_eval(model, band)
