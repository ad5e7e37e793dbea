"""A run re-derived with a later alignment (`realigned`): a run stores every pose it
measured at (each sample's commanded and read-back joint angles, each calibration's
read-back pose), so the pairs it measured can be recomputed through the true geometry
of an alignment file measured after it — as if its rig file had named that file from
the start. The raw readings stay as they are; everything derived from the pairs
(`gonio.analysis.calibrate`, `Measured`) follows.
"""

from __future__ import annotations

import hashlib
from dataclasses import replace
from pathlib import Path

import numpy as np

from gonio.rig import Rig
from gonio.store import Run

#: The sample columns of the recorded pair (`gonio.store.schema`).
_PAIR_COLUMNS = ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")


def realigned(run: Run, path: str | Path) -> Run:
    """``run`` with the alignment file at ``path`` (`ConfigError`, one line, on a bad
    one): the pairs of its samples (from the read-back angles) and of its calibrations
    (from the reference's read-back pose) through the true geometry the file gives, its
    plan's rig carrying that alignment, and its meta naming the file."""
    rig = run.plan.rig.realigned(path)
    assert rig.alignment_text is not None
    samples = dict(run.samples)
    if len(run):
        wi, wo = rig.forward(run.angles("read_back"), rig.alignment)
        for k, column in enumerate(_PAIR_COLUMNS):
            samples[column] = np.ascontiguousarray((wi if k < 3 else wo)[:, k % 3])
    events = tuple(
        replace(event, data={**event.data, **_pair(rig, event.data["pose_rad"])})
        if event.kind == "calibration" and "pose_rad" in event.data
        else event
        for event in run.events
    )
    meta = {
        **run.meta,
        "alignment_path": str(Path(path).resolve()),
        "alignment_text": rig.alignment_text.decode("utf-8"),
        "alignment_sha256": hashlib.sha256(rig.alignment_text).hexdigest(),
    }
    return replace(
        run,
        meta=meta,
        plan=replace(run.plan, rig=rig),
        samples=samples,
        events=events,
        _by_kind={},
    )


def _pair(rig: Rig, pose: list[float]) -> dict[str, list[float]]:
    """A calibration's pair at its read-back ``pose``, as the engine journals it."""
    wi, wo = rig.forward(np.array(pose, dtype=np.float64), rig.alignment)
    return {"wi": wi.tolist(), "wo": wo.tolist()}
