"""What the engine journals beside a reading, from what a detector may also say
(`drivers.base`): the range changes that fell inside it (an auto-ranging instrument)
and a lock-in's phase drift from the reference reading's.

Each is an event, not a fault: ``range`` (``old``, ``new``, ``at_s``, ``unit``) for each
range change, with the target whose reading it fell in (none during a calibration);
``phase`` (``phase_deg``, ``reference_deg``, ``drift_deg``, ``tolerance_deg``) for each
sample whose phase is further than the tolerance from the last reference reading's
(docs/reference/journal.md).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from drivers.base import Detector, phase_tolerance_deg, range_changes, reading_unit
from drivers.values import Reading
from gonio.store import Run


def phase_drift(phase_deg: float, reference_deg: float) -> float:
    """``phase_deg`` − ``reference_deg`` wrapped to [−180, 180) (°)."""
    return (phase_deg - reference_deg + 180.0) % 360.0 - 180.0


@dataclass
class ReadingWatch:
    """Follows one session's detector: the range changes journaled so far and the phase
    of the last reference reading (from the journal when a run resumes)."""

    detector: Detector
    offset_s: float = 0.0  # the detector clock's time + this = run time
    reference_deg: float | None = None
    _seen: int = 0

    @classmethod
    def of(cls, detector: Detector, offset_s: float, history: Run | None) -> ReadingWatch:
        """A watch of ``detector``, carrying on the phase reference of ``history``."""
        reference = None
        if history is not None:
            for event in history.of_kind("calibration"):
                phase = event.data["reference"].get("phase_deg")
                reference = reference if phase is None else float(phase)
        return cls(detector, offset_s, reference)

    def reference(self, reading: Reading) -> dict[str, Any]:
        """A reference reading's phase becomes the one samples are compared with; what
        the calibration event adds for it."""
        tolerance = phase_tolerance_deg(self.detector)
        if reading.phase_deg is None or tolerance is None:
            return {}
        self.reference_deg = reading.phase_deg
        return {"phase_tolerance_deg": tolerance}

    def events(self, reading: Reading | None) -> Iterator[tuple[str, dict[str, Any]]]:
        """(kind, data) of each event due after a measurement: the range changes since
        the last call and, for a sample's ``reading``, its phase drift."""
        changes = range_changes(self.detector)
        unit = reading_unit(self.detector)
        for change in changes[self._seen :]:
            yield (
                "range",
                {
                    "at_s": change.at_s + self.offset_s,
                    "old": change.old,
                    "new": change.new,
                    "unit": unit,
                },
            )
        self._seen = len(changes)
        tolerance = phase_tolerance_deg(self.detector)
        if reading is None or reading.phase_deg is None or tolerance is None:
            return
        if self.reference_deg is None:
            return
        drift = phase_drift(reading.phase_deg, self.reference_deg)
        if abs(drift) > tolerance:
            yield (
                "phase",
                {
                    "phase_deg": reading.phase_deg,
                    "reference_deg": self.reference_deg,
                    "drift_deg": drift,
                    "tolerance_deg": tolerance,
                },
            )
