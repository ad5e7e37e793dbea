"""The stream check of a serial detector (``gonio detector check-stream``): it streams
from the instrument, measures what ``docs/reference/serial_detector.md`` requires of a
streaming detector (the stop acknowledged after the last line, the first window begun
on the command, a steady rate, device timestamps, the latency, the lines' wire time, a
query answered afterwards) and writes the verdict beside the rig file, where hardware
fly support reads it (`fly_refusal`).

The package: :mod:`~gonio.workflows.stream_check.figures` (the requirements judged
from what was seen: pure), :mod:`~gonio.workflows.stream_check.probe` (the streams,
through the driver), :mod:`~gonio.workflows.stream_check.verdict` (the file and what fly
support reads of it) and :mod:`~gonio.workflows.stream_check.check` (`check_stream`).
"""

from gonio.workflows.stream_check.check import check_stream
from gonio.workflows.stream_check.figures import REQUIREMENTS, Limits, Requirement
from gonio.workflows.stream_check.verdict import (
    Verdict,
    fly_refusal,
    read_verdict,
    verdict_path,
)

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
