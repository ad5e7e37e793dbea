"""The composition root: the one place that wires backends (simulated, hardware,
rehearsal) to the acquisition engine, runs sessions (start, resume, dry run) and the
adaptive plan's passes, and simulates a plan end to end.

``from gonio.workflows import start, resume, simulate_plan`` is the programmatic
``gonio acquire`` / ``gonio simulate``.
"""

from gonio.workflows.preflight import Files, dry_run
from gonio.workflows.session import SessionResult, resume, start
from gonio.workflows.simulate import Result, simulate_plan

__all__ = [
    "Files",
    "Result",
    "SessionResult",
    "dry_run",
    "resume",
    "simulate_plan",
    "start",
]
