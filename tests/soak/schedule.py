"""When a soak kills its sessions and which meet a full disk: a seeded schedule."""

from __future__ import annotations

import random
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Kill:
    """When a session is killed: ``after`` new samples committed (0: from the spawn),
    then ``delay_s`` more."""

    after: int
    delay_s: float


@dataclass
class KillSchedule:
    """Seeded: ``kills`` kills spread over a run of ``targets`` (a quarter of them at
    any moment within ``startup_s`` of the spawn: opening, reading the run, restoring;
    the rest within 20 ms of a random number of new samples), and the sessions that
    meet a full disk (``disk_full`` of them, spread among the first sessions)."""

    seed: int
    kills: int
    targets: int
    disk_full: int = 0
    startup_s: float = 3.0
    disk_room: int = 4 << 20  # bytes a full disk leaves the session
    _rng: random.Random = field(init=False)
    _full: set[int] = field(init=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)
        spacing = max(2, self.kills + self.disk_full + 1)
        self._full = {2 + k * spacing // max(self.disk_full, 1) for k in range(self.disk_full)}

    def next_kill(self, *, planning: bool = False) -> Kill:
        """The next kill; ``planning``: of a session that plans first (a new run),
        killed only once it measures (a kill while it plans would only plan again)."""
        rng = self._rng
        if rng.random() < 0.25 and not planning:
            return Kill(0, rng.uniform(0.0, self.startup_s))
        mean = max(2, self.targets // max(self.kills, 1))
        return Kill(rng.randint(1, 2 * mean - 1), rng.uniform(0.0, 0.02))

    def disk_full_at(self, session: int) -> bool:
        """Whether spawn number ``session`` (0 = the first) meets a full disk."""
        return session in self._full
