"""The run journal: one SQLite file per run (`journal`: writing; `read`: `open_run`).
The layout is documented in docs/reference/journal.md."""

from gonio.store.journal import SCHEMA_VERSION, Journal, JournalError, UnjournaledValue
from gonio.store.read import Event, Run, open_run

__all__ = [
    "SCHEMA_VERSION",
    "Event",
    "Journal",
    "JournalError",
    "Run",
    "UnjournaledValue",
    "open_run",
]
