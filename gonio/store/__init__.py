"""The run journal: one SQLite file per run (`journal`: writing; `read`: `open_run`).
The layout is documented in docs/reference/journal.md."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.store.journal import SCHEMA_VERSION, Journal, JournalError, UnjournaledValue
from gonio.store.read import Event, Run, open_run

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.store import schema as schema
    from gonio.store.follow import RunFollower as RunFollower
    from gonio.store.follow import writer_holds as writer_holds
    from gonio.store.journal import dumps as dumps
    from gonio.store.journal import remove_run_file as remove_run_file
    from gonio.store.plan_view import PlanArrays as PlanArrays
    from gonio.store.plan_view import PlanInfo as PlanInfo
    from gonio.store.read import read_run as read_run
    from gonio.store.schema import commanded as commanded
    from gonio.store.schema import coordinate as coordinate
    from gonio.store.schema import read_back as read_back
    from gonio.store.schema import samples_table as samples_table

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "PlanArrays": "plan_view",
    "PlanInfo": "plan_view",
    "RunFollower": "follow",
    "commanded": "schema",
    "coordinate": "schema",
    "dumps": "journal",
    "read_back": "schema",
    "read_run": "read",
    "remove_run_file": "journal",
    "samples_table": "schema",
    "schema": "schema",
    "writer_holds": "follow",
}
__all__ = [
    "Event",
    "Journal",
    "JournalError",
    "Run",
    "SCHEMA_VERSION",
    "UnjournaledValue",
    "open_run",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
