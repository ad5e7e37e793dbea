"""Checks of a finished run: every target once, and two runs' samples bit for bit."""

from __future__ import annotations

from typing import Any

import numpy as np

from tests.soak.journal import Journal

#: Sample columns a resume may change: the session, the wall clock, the attempts (a
#: retried sample resumed after its failed attempt counts only its session's).
VOLATILE = frozenset({"session", "utc", "attempts"})


def same_samples(got: Journal, want: Journal) -> list[str]:
    """Where two runs' samples differ (every column but `VOLATILE`, bit for bit: floats
    compared as their IEEE bits) and their calibrations and skips; empty: identical."""
    out = []
    if set(got.samples) != set(want.samples):
        return ["the sample columns differ"]
    for name, value in want.samples.items():
        if name in VOLATILE:
            continue
        mine = got.samples[name]
        if len(mine) != len(value):
            return [f"{len(mine)} samples against {len(value)}"]
        floats = [v for v in value.tolist() if v is not None]
        if floats and all(isinstance(v, float) for v in floats):
            a = np.array([np.nan if v is None else v for v in mine.tolist()], dtype=np.float64)
            b = np.array([np.nan if v is None else v for v in value.tolist()], dtype=np.float64)
            differ = np.flatnonzero(a.view(np.int64) != b.view(np.int64))
        else:
            differ = np.flatnonzero(np.array([x != y for x, y in zip(mine, value, strict=True)]))
        if differ.size:
            out.append(f"{name}: {differ.size} samples differ (first: row {int(differ[0])})")

    def calibrations(j: Journal) -> list[Any]:
        return [(e.t_s, e.data.get("k"), e.data.get("reference"), e.data.get("dark"))
                for e in j.of_kind("calibration")]  # fmt: skip

    if calibrations(got) != calibrations(want):
        out.append("the calibrations differ")
    skips = [sorted(e.target for e in j.of_kind("skip") if e.target is not None)
             for j in (got, want)]  # fmt: skip
    if skips[0] != skips[1]:
        out.append("the skipped targets differ")
    return out


def exactly_once(journal: Journal) -> list[str]:
    """Every target of the plan measured once or skipped (by policy), never both."""
    n = journal.targets
    measured = journal.samples["target"].astype(np.int64)
    skips = [e.target for e in journal.of_kind("skip") if e.target is not None]
    out = []
    if len(set(measured.tolist())) != len(measured):
        out.append("a target measured twice")
    if len(set(skips)) != len(skips):
        out.append("a target skipped twice")
    both = set(measured.tolist()) & set(skips)
    if both:
        out.append(f"targets both measured and skipped: {sorted(both)[:10]}")
    missing = set(range(n)) - set(measured.tolist()) - set(skips)
    if missing:
        out.append(f"{len(missing)} targets neither measured nor skipped: {sorted(missing)[:10]}")
    return out
