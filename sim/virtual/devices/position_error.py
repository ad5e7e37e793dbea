"""The position_error effect of the simulated motors (`sim.virtual.devices.motors`): encoder
quantization, backlash and repeatability (`PositionModel`), the motors' state a
resumed run restores (`MotorState`), and where a plan's moves really end
(`planned_poses`, vectorized: what the instrument and `sim.virtual.simulate` share)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.rig import Rig
from gonio.scene import PositionErrorSpec, Scene
from gonio.types import FloatArray
from sim.virtual.physics import streams as streams_module


class PositionModel:
    """Encoder quantization, backlash and repeatability of the rig's axes (radians).

    The repeatability error is downstream of the encoder (a belt, a worm, a coupling):
    the encoder never sees it. Each axis draws a new one when it moves and keeps it
    while it stays put.
    """

    def __init__(self, rig: Rig, spec: PositionErrorSpec, streams: streams_module.Streams):
        self.spec = spec
        self.streams = streams
        axes = rig.bus_axes()
        self.tick = np.array([a.resolution_rad for a in axes])
        self.zero = np.array([a.zero_offset_rad for a in axes])
        self.backlash = math.radians(spec.backlash_deg)
        self.sigma = math.radians(spec.repeatability_deg)

    def quantize(self, angles: FloatArray) -> FloatArray:
        """The nearest encoder tick (joint angle, rad) of each axis."""
        if not self.spec.ticks:
            return np.asarray(angles, dtype=np.float64)
        steps = np.round((angles - self.zero) / self.tick)
        return np.asarray(self.zero + steps * self.tick, dtype=np.float64)

    def backlash_error(self, direction: FloatArray) -> FloatArray:
        """Joint minus encoder angle from backlash, after last moves in ``direction``
        (sign per axis, 0 before any move): the joint lags half the backlash behind."""
        return np.asarray(-0.5 * self.backlash * np.asarray(direction), dtype=np.float64)

    def repeatability_draw(self, index: np.ndarray, axes: int, start: int = 0) -> FloatArray:
        """(N, A) repeatability errors of a move made for samples ``index``; ``start`` is
        the draw offset of a sample's second, third … move."""
        if self.sigma == 0:
            return np.zeros((len(index), axes))
        n = self.streams.normal(index, streams_module.POSITION, axes, start=start)
        return np.asarray(self.sigma * n, dtype=np.float64)


@dataclass(frozen=True)
class MotorState:
    """What a resumed run needs of the motors: encoder angles at rest, the direction of
    each axis's last move (for backlash) and the joints' present error (rad)."""

    encoder: tuple[float, ...]
    direction: tuple[float, ...]
    repeatability: tuple[float, ...]


def _carry(values: FloatArray, where: np.ndarray) -> FloatArray:
    """Per column, ``values`` of the last row up to each row where ``where`` holds (0
    before the first)."""
    rows = np.arange(len(values))[:, None]
    last = np.maximum.accumulate(np.where(where, rows, -1), axis=0)
    filled = np.take_along_axis(values, np.maximum(last, 0), axis=0)
    return np.asarray(np.where(last >= 0, filled, 0.0), dtype=np.float64)


def planned_poses(
    rig: Rig,
    angles: FloatArray,
    scene: Scene,
    streams: streams_module.Streams,
    index: np.ndarray | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(goals the motors go to, true joint angles there, the previous goals), each
    (N, A), for joint ``angles`` (N, A) measured in order from the rig's home pose as
    samples ``index`` (default 0 … N − 1: their random streams)."""
    goal = np.asarray(angles, dtype=np.float64)
    error = np.zeros_like(goal)
    spec = scene.effects.position_error
    if spec is not None:
        model = PositionModel(rig, spec, streams)
        goal = np.clip(model.quantize(goal), rig.limits[:, 0], rig.limits[:, 1])
    previous = np.vstack([rig.home[None, :], goal[:-1]])
    if spec is not None:
        # Each axis keeps the direction and the repeatability draw of its last move.
        step = np.sign(goal - previous)
        moved = step != 0
        if index is None:
            index = np.arange(len(goal), dtype=np.int64)
        draws = model.repeatability_draw(index, goal.shape[1])
        error = model.backlash_error(_carry(step, moved)) + _carry(draws, moved)
    return goal, goal + error, previous
