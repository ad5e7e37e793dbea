"""`WindowOptics`: the optics of a stream's windows for the simulated detector — the
clock times a window's reading averages over (its middle, or with the scene's
``motion_blur`` the Gauss–Legendre nodes its smear needs), the joint angles there
(``pose_at``), and the geometric power at those poses.

Where ``pose_at`` gives the poses to come (``lookahead``: the simulated motors' planned
motion), the detector asks for the next windows' power in one vectorized pass
(`WindowOptics.ahead`, doubling the windows each time they are used up) instead of a
pass for every read; a window's reading then looks its poses up, and only an exactly
equal pose is a hit (a motion changed since computes afresh), so readings do not depend
on it: each pose's power is the same numbers computed alone or in a batch.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from drivers.base import StageTarget
from drivers.errors import DetectorError
from gonio.brdf import legendre
from sim.virtual.physics.optics import SceneOptics

#: Windows the first pass of a stream computes ahead; each later pass doubles it, to at
#: most `MOST_AHEAD`.
FIRST_AHEAD = 8
MOST_AHEAD = 1024


def blur_nodes(smear_deg: np.ndarray, max_step_deg: float, max_nodes: int) -> np.ndarray:
    """Time nodes per window (N,) for windows whose joints travel ``smear_deg`` (N,) °:
    ⌈smear / max_step⌉, at least 1 (a still window: its middle alone), at most
    ``max_nodes``."""
    n = np.ceil(np.asarray(smear_deg, dtype=np.float64) / max_step_deg - 1e-9)
    return np.clip(n, 1, max_nodes).astype(np.int64)


def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes in [0, 1] and weights summing to 1 of the n-point Gauss–Legendre rule (one
    node: the middle, weight 1 exactly)."""
    if n == 1:
        return np.array([0.5]), np.array([1.0])
    x, w = legendre(n)
    return 0.5 * (x + 1.0), 0.5 * w


class WindowOptics:
    """The optics of stream windows seen from the poses ``pose_at(t)`` gives (without
    it, the pose ``pose()`` gives now), for the axes ``axes`` in order."""

    def __init__(
        self,
        chain: SceneOptics,
        axes: tuple[str, ...],
        pose: Callable[[], Mapping[str, float]],
        pose_at: Callable[[float], Mapping[str, float]] | None,
        *,
        lookahead: bool,
    ) -> None:
        self.chain = chain
        self.axes = axes
        self._pose = pose
        self.pose_at = pose_at
        #: Whether ``pose_at`` gives the poses to come, so windows may be computed ahead.
        self.lookahead = lookahead and pose_at is not None
        self._ahead: dict[tuple[float, ...], float] = {}  # geometric power (W) by pose
        self._target: StageTarget = "sample"  # whose power ``_ahead`` holds
        self._next = FIRST_AHEAD  # windows the next pass computes ahead
        #: Window poses found computed ahead.
        self.hits = 0

    def forget(self) -> None:
        """Drop what was computed ahead (a new stream)."""
        self._ahead, self._next = {}, FIRST_AHEAD

    def poses(self, times: np.ndarray) -> np.ndarray:
        """Joint angles (len(times), A) at clock times (rad)."""
        poses = []
        for t in times.tolist():
            pose = self.pose_at(t) if self.pose_at is not None else self._pose()
            try:
                poses.append([float(pose[name]) for name in self.axes])
            except KeyError as exc:
                raise DetectorError(f"the pose has no angle for axis {exc.args[0]!r}") from None
        return np.array(poses, dtype=np.float64).reshape(len(times), len(self.axes))

    def time_nodes(
        self, started: np.ndarray, ended: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(times, weights, owner, nodes) of windows [started, ended] (N,) on the clock
        (s): the times (M,) whose poses a reading averages, their weights (M,) and
        windows (M,), and each window's node count (N,)."""
        middle = 0.5 * (started + ended)
        blur = self.chain.effects.motion_blur
        if blur is None or self.pose_at is None:
            nodes = np.ones(len(middle), dtype=np.int64)
            return middle, np.ones(len(middle)), np.arange(len(middle)), nodes
        ends = self.poses(np.concatenate([started, middle, ended])).reshape(3, len(middle), -1)
        travel = np.abs(ends[1] - ends[0]) + np.abs(ends[2] - ends[1])
        nodes = blur_nodes(np.degrees(travel.max(axis=1)), blur.max_step_deg, blur.max_nodes)
        rules = {n: gauss_legendre(n) for n in set(nodes.tolist())}
        times = np.concatenate(
            [
                [m] if n == 1 else a + (b - a) * rules[n][0]  # one node: the middle
                for a, m, b, n in zip(started, middle, ended, nodes.tolist(), strict=True)
            ]
        )
        weights = np.concatenate([rules[n][1] for n in nodes.tolist()])
        return times, weights, np.repeat(np.arange(len(middle)), nodes), nodes

    def ahead_count(self, due: int) -> int:
        """Windows the next pass computes: the ``due`` ones a read needs now and as many
        again as the last pass computed ahead (the first, `FIRST_AHEAD`)."""
        count = due + self._next
        self._next = min(2 * self._next, MOST_AHEAD)
        return count

    def ahead(self, started: np.ndarray, ended: np.ndarray, target: StageTarget) -> None:
        """Compute, in one pass, the geometric power at the poses of windows [started,
        ended] (N,) still to be read, as the motion stands now."""
        if target != self._target:
            self._ahead, self._target = {}, target
        poses = self.poses(self.time_nodes(started, ended)[0])
        power = self.chain.at_poses(poses, target)[2]
        self._ahead.update(zip(map(tuple, poses.tolist()), power.tolist(), strict=True))

    def power(self, poses: np.ndarray, target: StageTarget) -> np.ndarray:
        """The geometric power (W, (M,)) at window poses (M, A): looked up where it was
        computed ahead for ``target``, the rest in one pass."""
        if not self._ahead or target != self._target:
            return self.chain.at_poses(poses, target)[2]
        found = [self._ahead.get(pose) for pose in map(tuple, poses.tolist())]
        missing = [i for i, p in enumerate(found) if p is None]
        self.hits += len(found) - len(missing)
        if len(missing) == len(found):
            return self.chain.at_poses(poses, target)[2]
        power = np.array([np.nan if p is None else p for p in found], dtype=np.float64)
        if missing:
            power[missing] = self.chain.at_poses(poses[missing], target)[2]
        return power
