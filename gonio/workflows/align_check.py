"""The verdict of ``gonio align --check``: whether a short mirror scan's peaks agree with
an alignment file, each within three standard errors of the peak's location combined
with the alignment's own stated covariance."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.rig import Rig, as_alignment, miss, stated_covariance, vector
from gonio.types import FloatArray
from gonio.workflows.align_plan import PEAK_SIGMA_DEG


@dataclass(frozen=True)
class Verdict:
    """A check of an alignment: each peak's miss under it (rad, (M, 2)), its allowed
    bound (rad, (M, 2), three standard errors) and whether every miss is within."""

    misses_rad: FloatArray
    bounds_rad: FloatArray

    @property
    def holds(self) -> bool:
        return bool(np.all(np.abs(self.misses_rad) <= self.bounds_rad))

    def rows_deg(self) -> list[tuple[tuple[float, float], tuple[float, float]]]:
        """Each peak's |miss| and bound (°, two components each)."""
        misses, bounds = np.degrees(np.abs(self.misses_rad)), np.degrees(self.bounds_rad)
        return [
            ((m[0], m[1]), (b[0], b[1]))
            for m, b in zip(misses.tolist(), bounds.tolist(), strict=True)
        ]


def verdict(rig: Rig, peaks: FloatArray) -> Verdict:
    """Whether the peaks (M, A) agree with the rig's alignment: each miss within three
    times the peak's location error combined with the alignment's propagated error (the
    covariance its file states, `gonio.rig.alignment_fit.stated_covariance`, carried by
    central differences over each stated parameter's standard error)."""
    values, covariance = vector(rig, rig.alignment), stated_covariance(rig)
    misses = miss(rig, peaks, as_alignment(rig, values))
    errors = np.sqrt(np.diag(covariance))
    stated = np.flatnonzero(errors > 0)
    columns = []
    for i in stated:
        step = np.zeros_like(values)
        step[i] = errors[i]
        up = miss(rig, peaks, as_alignment(rig, values + step))
        down = miss(rig, peaks, as_alignment(rig, values - step))
        columns.append((up - down) / (2.0 * errors[i]))
    variance = np.full(misses.shape, math.radians(PEAK_SIGMA_DEG) ** 2)
    if columns:
        jac = np.stack(columns, axis=-1)  # (M, 2, S) per unit of each stated parameter
        block = covariance[np.ix_(stated, stated)]
        variance += np.einsum("mis,st,mit->mi", jac, block, jac)
    return Verdict(misses, 3.0 * np.sqrt(variance))


__all__ = ["Verdict", "verdict"]
