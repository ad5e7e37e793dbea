"""The stream check of a serial detector (``gonio detector check-stream``): it streams
from the instrument, measures what ``docs/reference/serial_detector.md`` requires of a
streaming detector (the stop acknowledged after the last line, the first window begun
on the command, a steady rate, device timestamps, the latency, the lines' wire time, a
query answered afterwards) and writes the verdict beside the rig file, where hardware
fly support reads it (`fly_refusal`).

The package: :mod:`~gonio.workflows.stream_check.figures` (the requirements, what is
observed, a verdict), :mod:`~gonio.workflows.stream_check.judge` (the requirements
judged from what was seen: pure), :mod:`~gonio.workflows.stream_check.probe` (the
streams, through the driver), :mod:`~gonio.workflows.stream_check.verdict` (the file and
what fly support reads of it) and :mod:`~gonio.workflows.stream_check.check`
(`check_stream`, loaded when first used: reading a verdict, as fly support does, loads
neither the probe nor the judging's scipy.stats).
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.workflows.stream_check.figures import REQUIREMENTS, Limits, Requirement
from gonio.workflows.stream_check.verdict import (
    Verdict,
    fly_refusal,
    read_verdict,
    verdict_path,
)

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.workflows.stream_check.check import check_stream as check_stream

#: The names of the face that load with their module when first used (`gonio.faces`).
WHERE = {"check_stream": "check"}
__getattr__, __dir__ = lazy_face(__name__, WHERE)

__all__ = [
    "REQUIREMENTS",
    "Limits",
    "Requirement",
    "Verdict",
    "check_stream",
    "fly_refusal",
    "read_verdict",
    "verdict_path",
]
