"""The read model of a run shared by ``gonio serve`` and ``gonio watch``: a run file
followed as it grows through the journal's read API (`gonio.store.follow.RunFollower`:
what was committed since the last read, checked as `gonio.store.open_run` checks it),
and the run's state as the views name it (what is shown of it: `gonio.live.views`).

State: ``running`` while a ``gonio acquire`` holds the run file's lock, ``paused`` if
it holds it and its last pause (a request, or a health condition) has not been resumed
yet; otherwise ``completed``, ``stopped`` (ended early, resumable), or ``fault`` (a
motor fault, an abort or a full disk: resumable too).
"""

from __future__ import annotations

from gonio.store import PlanArrays, PlanInfo, RunFollower, writer_holds

#: Outcomes of a session that ended on a fault (resumable all the same).
_FAULTS = frozenset({"fault", "aborted", "journal"})

__all__ = ["LiveRun", "PlanArrays", "PlanInfo", "writer_holds"]


class LiveRun(RunFollower):
    """A run file followed as it grows (`RunFollower`), with its state (module
    docstring). `JournalError` (one line) if it is not a readable run file."""

    def state(self) -> str:
        """``running``, ``paused``, ``completed``, ``stopped`` or ``fault`` (module
        docstring)."""
        if self.writing:
            current = self.sessions[-1].id if self.sessions else None
            for e in reversed(self.events):
                if e.session != current:
                    break
                if e.kind == "pause":
                    return "paused"
                if e.kind in ("resume", "start"):
                    return "running"
            return "running"
        if self.complete:
            return "completed"
        ended = [s for s in self.sessions if s.outcome is not None]
        if ended and ended[-1].outcome in _FAULTS:
            return "fault"
        return "stopped"
