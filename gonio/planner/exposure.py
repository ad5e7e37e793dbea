"""Exposure and averaging per target, constant or scaled by the expected signal."""

from __future__ import annotations

import numpy as np

from gonio.planner.schema import ExposureSpec
from gonio.radiometry import SourceKind, relative_geometry
from gonio.types import FloatArray


def exposures(
    spec: ExposureSpec, wi: FloatArray, wo: FloatArray, source_kind: SourceKind
) -> tuple[FloatArray, np.ndarray]:
    """(exposure time s, averages) per target.

    With ``adapt``, the expected signal s = f(ωi, ωo) · g of the named material (g the
    radiometric chain's direction dependence for the rig's ``source_kind``: cos θo for a
    collimated beam, whose whole power lands on the sample; cos θi for a point source)
    sets exposure = seconds × s_ref / s (s_ref: the median s of the plan), clipped to
    [min_s, max_s]; the averages grow the same way up to ``max_averages`` once the
    exposure is at its maximum.
    """
    n = len(wi)
    base = np.full(n, spec.seconds)
    count = np.full(n, spec.averages, dtype=np.int64)
    if spec.adapt is None:
        return base, count
    value = np.asarray(spec.adapt.model().eval(wi, wo), dtype=np.float64)
    if value.ndim == 2:  # RGB: the mean of the channels
        value = value.mean(axis=1)
    signal = value * relative_geometry(source_kind, wi, wo)
    positive = signal[signal > 0]
    reference = float(np.median(positive)) if positive.size else 1.0
    factor = reference / np.maximum(signal, reference * 1e-9)
    wanted = spec.seconds * factor
    time_s = np.clip(wanted, spec.adapt.min_s, spec.adapt.max_s)
    extra = np.ceil(wanted / time_s - 1e-9).astype(np.int64)
    averages = np.clip(
        spec.averages * extra, spec.averages, max(spec.averages, spec.adapt.max_averages)
    )
    return np.asarray(time_s, dtype=np.float64), averages
