"""The injector the simulated devices consult: which of a scene's ``faults:`` rules
(`gonio.scene.FaultRule`, where each kind is described) fires at which attempt of which
sample, drawn from the run's counter-based streams, so a resumed run sees exactly the
faults an uninterrupted one does."""

from __future__ import annotations

import numpy as np

from gonio.scene import FaultRule
from sim.virtual.physics.streams import FAULT, Streams


class FaultInjector:
    """Which rule fires at which attempt of which sample (pure function of the rules,
    the run's streams, the sample index and the attempt number)."""

    def __init__(self, rules: tuple[FaultRule, ...], streams: Streams) -> None:
        self.rules = rules
        self.streams = streams
        self._at = [frozenset(r.at) if r.at is not None else None for r in rules]

    def __bool__(self) -> bool:
        return bool(self.rules)

    def fired(self, index: int, attempt: int, kinds: frozenset[str]) -> FaultRule | None:
        """The first rule of ``kinds`` that fires at ``attempt`` (0 = first) of sample
        ``index``, or None (a rule fires at the first ``burst`` attempts; a negative
        attempt never)."""
        if attempt < 0:
            return None
        for k, (rule, at) in enumerate(zip(self.rules, self._at, strict=True)):
            if rule.kind not in kinds or attempt >= rule.burst:
                continue
            if at is not None:
                if index in at:
                    return rule
            elif rule.rate and self._draw(index, k) < rule.rate:
                return rule
        return None

    def _draw(self, index: int, rule: int) -> float:
        u = self.streams.uniform(np.array([index]), FAULT + rule, 1)
        return float(u[0, 0])
