"""The plan as data: `Plan` (targets in measuring order, frozen), its `Summary`, and the
hashes that name the texts a plan was built from (`content_hash`, `sha256`).

A `Plan` is the same for a given plan file, rig and seed on any machine unless the
ordering's wall-clock safety cap binds (the summary says so). `gonio.planner.builder`
makes one; `gonio.planner.stored` stores it and reads it back bit for bit.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

import numpy as np

from gonio.planner.ordered import Ordering, Stop
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig
from gonio.types import FloatArray

#: Framing of `content_hash` (the version names the framing, not gonio's).
_HASH_MAGIC = b"gonio content v1\n"


def content_hash(
    plan_text: bytes,
    rig_text: bytes,
    scene_text: bytes | None = None,
    alignment_text: bytes | None = None,
) -> str:
    """SHA-256 (hex) of a plan file's, a rig file's and optionally a scene file's and the
    rig's alignment file's bytes, for the run journal: what a run measured, named by what
    it was made from.

    Framing: the bytes ``gonio content v1\\n``, then for each of plan, rig, scene the
    part's name, a space, its length in bytes in decimal (``-`` for no scene), a newline
    and the bytes themselves; then, only for a rig with an alignment file, the part
    ``alignment`` framed the same way (so a hash made without one is unchanged). The
    lengths make the split unambiguous: ("ab", "c") and ("a", "bc") hash differently, and
    no scene differs from an empty one.
    """
    h = hashlib.sha256(_HASH_MAGIC)
    parts = [("plan", plan_text), ("rig", rig_text), ("scene", scene_text)]
    if alignment_text is not None:
        parts.append(("alignment", alignment_text))
    for name, text in parts:
        h.update(f"{name} {'-' if text is None else len(text)}\n".encode("ascii"))
        if text is not None:
            h.update(text)
    return h.hexdigest()


def sha256(text: bytes) -> str:
    """SHA-256 (hex) of one file's bytes."""
    return hashlib.sha256(text).hexdigest()


@dataclass(frozen=True)
class FlyFigures:
    """A fly plan's figures (`gonio.planner.fly`). Times in seconds, angles in degrees.

    ``stop_and_go_s``: the same readings measured stop-and-go at the same poses in the
    same order (trapezoidal moves, settle and one integration each). ``coverage_tv``:
    the total-variation distance between the readings' histogram in the plan's
    coordinates and the uniform density over what the rig reaches (``coverage_bins``
    bins a coordinate); ``coverage_tv_uniform``: the same figure of a uniform (Sobol)
    stop-and-go plan of as many targets, its sampling noise. ``coverage_gap``: the
    radius of the largest ball (coordinates scaled to the unit box) centred on a
    reachable point that holds no reading; ``coverage_gap_uniform``: the same of the
    uniform plan. ``streamed``: readings the detector streams, of which the plan keeps
    ``kept`` as its targets (the thinning that makes them uniform)."""

    lines: int  # sweep lines laid out through the anchors
    segments: int  # constant-velocity segments (a line's reachable runs)
    integration_s: float
    period_s: float
    blur_deg: float  # the budget
    smear_max_deg: float  # the largest smear of a reading (≤ blur_deg)
    velocity_min_deg_s: float  # sweep velocities of the swept axis
    velocity_max_deg_s: float
    cruise_s: float  # time at constant velocity, summed
    ramps_s: float  # accelerating and decelerating, summed
    moves_s: float  # moves between sweeps (settles included)
    stop_and_go_s: float
    coverage_tv: float
    coverage_tv_uniform: float
    coverage_bins: int
    streamed: int = 0  # readings streamed during the sweeps (kept + thinned out)
    coverage_gap: float = 0.0  # largest empty ball's radius (unit box) among the reach
    coverage_gap_uniform: float = 0.0  # the same of the uniform stop-and-go plan


#: The model a plan's times were predicted with: ``rig``, the rig file's velocities and
#: accelerations and no bus (simulated motors, and every plan stored before the field
#: existed); ``dynamixel``, the rates the motors' profile registers hold and the bus's
#: wire time at the rig's baud rate (`Rig.motion_rates`, `Rig.bus_time`).
TimingModel = Literal["rig", "dynamixel"]


@dataclass(frozen=True)
class Summary:
    """Counts and times of a plan. Times in seconds; the generation-order and MST
    figures are None unless the plan was built with ``bounds=True``."""

    requested: int  # points placed in the coordinate box
    invalid: int  # outside the parametrization's domain
    refused: Mapping[str, int]  # unreachable, by reason (read-only)
    kept: int
    travel_s: float  # ordered, moves only
    dwell_s: float  # settle + exposure × averages, summed
    moves: int = 0  # improving moves of the ordering's descents
    max_moves: int = 0  # the budget of improving moves
    kicks: int = 0  # kicks of the iterated local search tried
    kicks_kept: int = 0  # … that shortened the path
    max_kicks: int = 0  # the budget of kicks
    stopped: Stop = "converged"  # why the ordering stopped
    time_cap_s: float = 0.0  # the ordering's wall-clock safety cap
    grid_shape: tuple[int, ...] | None = None
    target: int | None = None  # the kept targets asked for, if the plan gave a number
    naive_travel_s: float | None = None  # in generation order (bounds only)
    # Lower bounds on the moves of any order with any choice of solutions (bounds only):
    lower_bound_travel_s: float | None = None  # Held–Karp 1-tree (`gonio.planner.bounds`)
    mst_travel_s: float | None = None  # the minimum spanning tree (cheaper, looser)
    lower_bound_exact: bool | None = None  # False: memory forced a weaker MST somewhere
    # An adaptive plan's second pass: how it was placed and why (`gonio.planner.choice`).
    second_pass: str | None = None
    fly: FlyFigures | None = None  # a fly plan's figures
    bus_s: float = 0.0  # the motor bus's part of the steps, summed (`Rig.bus_time`)
    timing: TimingModel = "rig"  # the model of the times (`TimingModel`)

    def __post_init__(self) -> None:
        object.__setattr__(self, "refused", MappingProxyType(dict(self.refused)))

    @property
    def converged(self) -> bool:
        """The local search ended with no improving move left."""
        return self.stopped == "converged"

    @property
    def total_s(self) -> float:
        """The predicted duration: moves, dwells and the bus's part of the steps."""
        return self.travel_s + self.dwell_s + self.bus_s

    @property
    def naive_total_s(self) -> float | None:
        if self.naive_travel_s is None:
            return None
        return self.naive_travel_s + self.dwell_s + self.bus_s

    @property
    def lower_bound_s(self) -> float | None:
        if self.lower_bound_travel_s is None:
            return None
        return self.lower_bound_travel_s + self.dwell_s + self.bus_s


#: The array fields of a `Plan` and their dtypes.
ARRAYS: dict[str, type[np.generic]] = {
    "coords": np.float64,
    "generated": np.int64,
    "wi": np.float64,
    "wo": np.float64,
    "angles": np.float64,
    "exposure_s": np.float64,
    "averages": np.int64,
    "travel_s": np.float64,
    "arrival_s": np.float64,
}


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal dtype, shape and every byte (so −0.0 ≠ 0.0: identical, not just equal)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


#: The array fields of `Sweeps` and their dtypes (one row per segment, measuring order).
SWEEP_ARRAYS: dict[str, type[np.generic]] = {
    "start": np.float64,
    "entry": np.float64,
    "exit": np.float64,
    "stop": np.float64,
    "velocity": np.float64,
    "first": np.int64,
    "count": np.int64,
    "cruise_at_s": np.float64,
    "streamed": np.int64,
}
#: The array fields of `Sweeps` that locate each segment's trajectory in ``path`` (one row
#: per segment; a count of 0: a sweep of one axis at constant velocity, no trajectory).
PATH_ARRAYS: dict[str, type[np.generic]] = {"path_first": np.int64, "path_count": np.int64}


def _no_rows() -> np.ndarray:
    return np.zeros(0, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class Sweeps:
    """The segments of a fly plan in measuring order. Angles in radians (rows in
    ``rig.axes`` order), velocities in rad/s, times in seconds from the run's start.

    Each segment is commanded as one move from ``start`` (at rest) to ``stop`` (at rest)
    with the axes' velocity ``velocity`` between ``entry`` (reached at ``cruise_at_s``)
    and ``exit``: readings only there, ``count`` of them, the plan's targets
    ``first`` … ``first + count − 1``. The detector streams ``streamed`` readings
    (≥ ``count``) there, the j-th integrating from ``cruise_at_s + j · period_s`` for
    ``integration_s``; the targets are those the coverage thinning kept (in stream
    order, target i being stream reading ``round((arrival_s[i] − cruise_at_s) /
    period_s)``; the first and the last streamed readings are always targets).

    A path segment (``path_count`` > 0, `gonio.planner.fly.paths`) is instead a
    trajectory every axis follows: the set-points ``path[path_first : path_first +
    path_count]`` (rad), one every ``path_period_s`` from ``start`` (at rest, set-point
    0, due at ``cruise_at_s``) to ``stop`` (at rest); ``entry`` = ``start``, ``exit`` =
    ``stop``, ``velocity`` zero, and the stream's slot j integrates from ``cruise_at_s +
    j · period_s`` along the path.

    The segments' targets are the plan's first ``count.sum()``; any after them are
    stop-and-go targets measured after the last segment (a mixed plan)."""

    start: FloatArray  # (S, A) the run-up pose (at rest)
    entry: FloatArray  # (S, A) where the constant velocity begins
    exit: FloatArray  # (S, A) where it ends
    stop: FloatArray  # (S, A) the overrun pose (at rest)
    velocity: FloatArray  # (S, A) rad/s during the constant-velocity part
    first: np.ndarray  # (S,) int64
    count: np.ndarray  # (S,) int64
    cruise_at_s: FloatArray  # (S,)
    streamed: np.ndarray  # (S,) int64 readings streamed at constant velocity (≥ count)
    period_s: float
    integration_s: float
    path_first: np.ndarray = field(default_factory=_no_rows)  # (S,) int64; none: no paths
    path_count: np.ndarray = field(default_factory=_no_rows)  # (S,) int64
    path: FloatArray = field(default_factory=_no_rows)  # (P, A) set-points of the paths, rad
    path_period_s: float = 0.0

    def __post_init__(self) -> None:
        n = len(self.first)
        if not len(self.path_count):
            object.__setattr__(self, "path_first", np.zeros(n, dtype=np.int64))
            object.__setattr__(self, "path_count", np.zeros(n, dtype=np.int64))
        for name, dtype in {**SWEEP_ARRAYS, **PATH_ARRAYS}.items():
            value = np.array(getattr(self, name), dtype=dtype)
            if value.shape[:1] != (n,):
                raise ValueError(f"Sweeps.{name}: expected {n} rows, got shape {value.shape}")
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        axes = np.shape(self.start)[1] if np.ndim(self.start) == 2 else 0
        path = np.array(self.path, dtype=np.float64).reshape(-1, axes)
        path.setflags(write=False)
        object.__setattr__(self, "path", path)

    @property
    def swept(self) -> int:
        """How many of the plan's targets the segments read (the first ones)."""
        return int(np.asarray(self.count).sum())

    @property
    def has_paths(self) -> bool:
        """Whether any segment follows a trajectory (`path_count` > 0)."""
        return bool(np.any(np.asarray(self.path_count) > 0))

    def set_points(self, k: int) -> FloatArray:
        """Segment ``k``'s trajectory set-points (K, A) rad (empty for an axis sweep)."""
        a = int(self.path_first[k])
        return np.asarray(self.path[a : a + int(self.path_count[k])])

    def __len__(self) -> int:
        return len(self.first)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Sweeps):
            return NotImplemented
        return (
            self.period_s == other.period_s
            and self.integration_s == other.integration_s
            and self.path_period_s == other.path_period_s
            and all(
                same_bits(getattr(self, n), getattr(other, n))
                for n in (*SWEEP_ARRAYS, *PATH_ARRAYS, "path")
            )
        )

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True, eq=False)
class Plan:
    """Targets in measuring order. Angles in radians, times in seconds.

    Frozen: every array is a private read-only copy (change a plan with
    `dataclasses.replace`, which makes a new one). ``==`` is "the same stored plan":
    spec, plan and rig texts, coordinate names and summary equal, every array identical
    bit for bit; ``ordering`` (the search's diagnostics) and the wall times (figures of
    the machine and its load) are not stored and left out.
    """

    spec: PlanSpec
    rig: Rig
    coordinate_names: tuple[str, ...]
    coords: FloatArray  # (N, d) the planned coordinates
    generated: np.ndarray  # (N,) int64, each target's position among the points placed
    wi: FloatArray  # (N, 3) the pair measured (sample frame)
    wo: FloatArray
    angles: FloatArray  # (N, A) in rig.axes order
    exposure_s: FloatArray
    averages: np.ndarray  # (N,) int64
    travel_s: FloatArray  # move into each target
    arrival_s: FloatArray  # predicted time of arrival at each target
    summary: Summary
    plan_text: bytes  # the plan file's bytes (for a spec made in code: `spec_text`)
    ordering: Ordering | None = None  # the search's figures (constructed length, …)
    ordering_s: float | None = None  # wall time spent ordering (None: read back)
    bound_wall_s: float | None = None  # wall time spent on the lower bounds (bounds only)
    sweeps: Sweeps | None = None  # a fly plan's segments (None: stop-and-go)

    def __post_init__(self) -> None:
        n = len(self.coords)
        for name, dtype in ARRAYS.items():
            value = np.array(getattr(self, name), dtype=dtype)  # a copy nobody else holds
            if value.shape[:1] != (n,):
                raise ValueError(f"Plan.{name}: expected {n} rows, got shape {value.shape}")
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return len(self.coords)

    @property
    def is_fly(self) -> bool:
        """Readings taken while the axes move (`sweeps`), not stop-and-go."""
        return self.sweeps is not None

    @property
    def is_survey(self) -> bool:
        """The first pass of an adaptive plan, its second still to be planned
        (`gonio.planner.two_pass`)."""
        s = self.spec.sampling
        return s.strategy == "adaptive" and s.target is not None and len(self) < s.target

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Plan):
            return NotImplemented
        return (
            self.spec == other.spec
            and self.plan_text == other.plan_text
            and self.rig.text == other.rig.text
            and self.coordinate_names == other.coordinate_names
            and self.summary == other.summary
            and all(same_bits(getattr(self, n), getattr(other, n)) for n in ARRAYS)
            and self.sweeps == other.sweeps
        )

    __hash__ = None  # type: ignore[assignment]

    def content_hash(self, scene_text: bytes | None = None) -> str:
        """`content_hash` of the texts this plan was built from (and a scene's)."""
        return content_hash(self.plan_text, self.rig.text, scene_text, self.rig.alignment_text)
