"""Exposure and averaging per target, constant or scaled by the expected signal."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gonio.config import ConfigError, line_of, read_yaml
from gonio.planner.schema import ExposureSpec, PlanSpec
from gonio.radiometry import SourceKind, relative_geometry
from gonio.rig import Rig
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


def check_detector(spec: PlanSpec, rig: Rig, where: str, text: bytes | None) -> None:
    """`ConfigError` unless every exposure and averaging count the plan can ask for is
    one the rig's detector accepts (``detector.exposure_range_s``, ``max_averages``)."""
    detector = rig.spec.detector
    lo, hi = detector.exposure_range_s
    e = spec.exposure
    problems: list[tuple[tuple[str, ...], str]] = []
    if e.adapt is None:
        if not lo <= e.seconds <= hi:
            problems.append((("exposure", "seconds"), f"{e.seconds:g} s"))
    else:
        for name in ("min_s", "max_s"):
            value = getattr(e.adapt, name)
            if not lo <= value <= hi:
                problems.append((("exposure", "adapt", name), f"{value:g} s"))
    for path, got in problems:
        line = _line_in(where, text, path)
        raise ConfigError(
            f"{where}{line}: {'.'.join(path)}: {got} is outside the detector's exposure range "
            f"[{lo:g}, {hi:g}] s (the rig file's detector.exposure_range_s)"
        )
    most = max(e.averages, e.adapt.max_averages if e.adapt is not None else 0)
    if detector.max_averages is not None and most > detector.max_averages:
        path = ("exposure", "averages" if e.averages == most else "adapt")
        if path[1] == "adapt":
            path = ("exposure", "adapt", "max_averages")
        raise ConfigError(
            f"{where}{_line_in(where, text, path)}: {'.'.join(path)}: up to {most} averages; "
            f"the detector takes at most {detector.max_averages} (the rig file's "
            "detector.max_averages)"
        )


def _line_in(where: str, text: bytes | None, path: tuple[str, ...]) -> str:
    """``:LINE`` of ``path`` in the plan file's text, or nothing."""
    if text is None:
        return ""
    try:
        line = line_of(read_yaml(Path(where), text)[1], path)
    except ConfigError:
        return ""
    return "" if line is None else f":{line}"
