"""The transforms of BRDF values a reconstruction interpolates
(docs/explanations/reconstruction.md).

A transform maps values f (sr⁻¹, (N, C): one column per channel) at pairs to g,
interpolated instead of f, and back. Each also gives its derivative both ways, which
carries a 1σ uncertainty across
(σg = |dg/df| σf at a sample, σf = |df/dg| σg at a query). Negative readings (noise
around 0) count as 0 in the logarithmic ones: a BRDF is never negative.

- ``identity``: g = f.
- ``log1p``: g = log(1 + f·1 sr) — linear for dim values, logarithmic for peaks.
- ``log``: g = log(f + ε), ε = `LOG_FLOOR` — relative errors, whatever the level.
- ``log_cos``: g = log(f cos θi + ε), ε = `LOG_COS_FLOOR` — the reflected radiance
  factor, which tames the 1/cos θi growth of grazing values.
- ``ratio`` (the model+residual method): g = log((f + ε)/(m + ε)) for a model m,
  ε = `RATIO_FLOOR`; the residual ratio of the data to the model.
"""

from __future__ import annotations

import numpy as np

from gonio.brdf import LOG_FLOOR
from gonio.errors import GonioError, UnknownNameError
from gonio.types import BrdfEval, FloatArray

#: ε of ``log_cos`` (sr⁻¹): below it, values are interpolated linearly, not in log.
LOG_COS_FLOOR = 1e-2
#: ε of ``ratio`` (sr⁻¹): keeps the ratio finite where the model is 0.
RATIO_FLOOR = 1e-3
#: cos θi used in place of smaller ones (θi within 2e-3° of grazing).
COS_FLOOR = 1e-6


def _channels(a: FloatArray) -> FloatArray:
    """A per-pair factor (N,) as a column (N, 1) that meets values (N, C)."""
    return a[:, None] if a.ndim == 1 else a


class Transform:
    """g = T(f) at pairs (wi, wo), each (N, 3); values f and g are (N, C)."""

    name = "identity"

    def encode(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.asarray(f, dtype=np.float64)

    def slope(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        """|dg/df| at the samples' values."""
        return np.ones_like(f)

    def decode(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.asarray(g, dtype=np.float64)

    def gain(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        """|df/dg| at interpolated values."""
        return np.ones_like(g)


class Log1p(Transform):
    name = "log1p"

    def encode(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.log1p(np.maximum(f, 0.0))

    def slope(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return 1.0 / (1.0 + np.maximum(f, 0.0))

    def decode(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.expm1(g)

    def gain(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.exp(g)


class Log(Transform):
    name = "log"

    def encode(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.log(np.maximum(f, 0.0) + LOG_FLOOR)

    def slope(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return 1.0 / (np.maximum(f, 0.0) + LOG_FLOOR)

    def decode(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.exp(g) - LOG_FLOOR

    def gain(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.exp(g)


class LogCos(Transform):
    name = "log_cos"

    @staticmethod
    def _cos(wi: FloatArray) -> FloatArray:
        return _channels(np.maximum(wi[:, 2], COS_FLOOR))

    def encode(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.log(np.maximum(f, 0.0) * self._cos(wi) + LOG_COS_FLOOR)

    def slope(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        c = self._cos(wi)
        return c / (np.maximum(f, 0.0) * c + LOG_COS_FLOOR)

    def decode(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return (np.exp(g) - LOG_COS_FLOOR) / self._cos(wi)

    def gain(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.exp(g) / self._cos(wi)


class Ratio(Transform):
    """The residual of data to a model (any object with ``eval(wi, wo)``)."""

    name = "ratio"

    def __init__(self, model: BrdfEval) -> None:
        self.model = model

    def _shifted_model(self, wi: FloatArray, wo: FloatArray, like: FloatArray) -> FloatArray:
        m = _channels(np.asarray(self.model(wi, wo), dtype=np.float64))
        if m.shape[1] not in (1, like.shape[1]):
            raise GonioError(
                f"model+residual: the model gives {m.shape[1]} channels and the measurement "
                f"{like.shape[1]}; expected a model of the measurement's band(s)"
            )
        return np.maximum(m, 0.0) + RATIO_FLOOR

    def encode(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return np.log((np.maximum(f, 0.0) + RATIO_FLOOR) / self._shifted_model(wi, wo, f))

    def slope(self, f: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return 1.0 / (np.maximum(f, 0.0) + RATIO_FLOOR)

    def decode(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return self._shifted_model(wi, wo, g) * np.exp(g) - RATIO_FLOOR

    def gain(self, g: FloatArray, wi: FloatArray, wo: FloatArray) -> FloatArray:
        return self._shifted_model(wi, wo, g) * np.exp(g)


#: The transforms a reconstruction may interpolate (``ratio`` needs a model: it is
#: the model+residual method's, not chosen by name).
TRANSFORMS: dict[str, type[Transform]] = {t.name: t for t in (Transform, Log1p, Log, LogCos)}


def get(name: str) -> Transform:
    """The transform called ``name`` (one of `TRANSFORMS`)."""
    try:
        return TRANSFORMS[name]()
    except KeyError:
        raise UnknownNameError(
            f"unknown transform {name!r}; expected one of {', '.join(TRANSFORMS)}"
        ) from None
