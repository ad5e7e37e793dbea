"""The composition root: the one place that wires backends (simulated, hardware,
rehearsal) to the acquisition engine, runs sessions (start, resume, dry run) and the
adaptive plan's passes, and simulates a plan end to end.

``from gonio.workflows import start, resume, simulate_plan`` is the programmatic
``gonio acquire`` / ``gonio simulate``.
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.workflows.preflight import Files, dry_run
from gonio.workflows.session import SessionResult, resume, start
from gonio.workflows.simulate import Result, simulate_plan

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.workflows import align as align
    from gonio.workflows import align_check as align_check
    from gonio.workflows import backends as backends
    from gonio.workflows import preflight as preflight
    from gonio.workflows import session as session
    from gonio.workflows.adaptive import estimate as estimate
    from gonio.workflows.align import Scan as Scan
    from gonio.workflows.align_check import Verdict as Verdict
    from gonio.workflows.align_plan import ScanSettings as ScanSettings
    from gonio.workflows.align_plan import nominal_poses as nominal_poses
    from gonio.workflows.align_plan import reachable as reachable
    from gonio.workflows.preflight import refuse_fly_detector as refuse_fly_detector
    from gonio.workflows.rehearsal import rehearsal_devices as rehearsal_devices
    from gonio.workflows.stream_check import check_stream as check_stream
    from gonio.workflows.stream_check import verdict_path as verdict_path

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Scan": "align",
    "ScanSettings": "align_plan",
    "Verdict": "align_check",
    "align": "align",
    "align_check": "align_check",
    "backends": "backends",
    "check_stream": "stream_check",
    "estimate": "adaptive",
    "nominal_poses": "align_plan",
    "preflight": "preflight",
    "reachable": "align_plan",
    "refuse_fly_detector": "preflight",
    "rehearsal_devices": "rehearsal",
    "session": "session",
    "verdict_path": "stream_check",
}
__all__ = [
    "Files",
    "Result",
    "SessionResult",
    "dry_run",
    "resume",
    "simulate_plan",
    "start",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
