"""A fly sweep's streams merged into samples: pure estimation, no device I/O
(docs/explanations/acquisition.md).

`merge`: each reading's joint angles are the polled positions interpolated (linearly,
per axis, on each poll's mid-time) at the middle of its integration window; its smear is
the joint-space path covered during the window (rad); its timing uncertainty is the
stamps' jitter (the request-to-reply spans of the two polls interpolated, weighted as
they are, `interpolated_span`, / √12: the positions are sampled somewhere in them; and
the readings' stamp slack / √12, `stamp_slack`, in quadrature) × the angular speed
there (rad); polls slower than `SLOW_POLL` × the median are left out.
Only readings whose whole window lies inside the constant-velocity part (the swept axis
between the entry and exit poses, give or take one period's travel: the stream's phase is
the device's) and between two polls whose straight line the commanded motion supports
(`bracketed`: both in the constant-velocity part, or close enough in time that a ramp
between them bends the path by at most `RAMP_BIAS` of a period's travel, `ramp_gap`,
from the planned acceleration) are placed so. A window inside that part whose polls do
not support it (a host stall about a ramp) is placed on the lines at the commanded
velocity through the part's polls (`cruise_offsets`, from `CRUISE_POLLS` of them; its
smear the speed × the window), else not at all. Each is matched to a stream slot j (the
j-th reading streamed at constant velocity, planned mid-pose entry + v (j period +
integration / 2)). The readings are consecutive windows (`window_numbers`: from the
device's timestamps, else their order), so one shift maps them all to slots: the
median, over the readings inside, of the window number less the slot their position
along the swept axis gives at the commanded velocity (robust to the scatter of each
position; a velocity off the plan's shows as read-back angles drifting from the
targets' along the sweep). The plan's targets are the slots its coverage thinning kept
(`target_slots`); a matched reading in a slot that is no target stays in the journal's
raw ``stream`` table only: the sweep's samples are exactly the plan's targets read
(`derive`).

`merge_path`: a path sweep's (a trajectory every axis follows) readings get their angles
the same way; their slots by time since the trajectory's origin (set-point 0 due):
through one shift of the window numbers when the device stamps its windows, else each
reading's round((started − origin) / period_s). Only readings whose whole window lies
between the first and the last poll are matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from drivers.stream import StreamReading
from drivers.values import StampedPositions
from gonio.planner import Sweeps
from gonio.types import FloatArray

#: A poll whose request-to-reply span exceeds this many times the sweep's median is not
#: interpolated (when it happened within the span is too loosely known).
SLOW_POLL = 3.0
#: The largest share of one period's travel that interpolating two polls across a ramp
#: (accelerating between them, not at constant velocity) may put a reading off by.
RAMP_BIAS = 0.1
#: The polls in a sweep's constant-velocity part that place its windows on the line at
#: the commanded velocity where the polls about a window do not (`cruise_offsets`).
CRUISE_POLLS = 3


@dataclass(frozen=True)
class RawSweep:
    """A sweep's raw streams: the polls and the stream's readings (host clock, s); a
    sweep's ``velocities`` (rad/s) are those the bus commanded (a register holds them in
    steps: a Dynamixel's is 0.229 rev/min of the motor), not the plan's."""

    polls: list[StampedPositions]
    readings: list[StreamReading]
    started_s: float
    ended_s: float
    origin_s: float | None = None  # a path sweep's: when its set-point 0 was due
    velocities: dict[str, float] | None = None  # a sweep's, as commanded


@dataclass(frozen=True)
class Merged:
    """The matched readings of a sweep, in stream order: ``index`` into the raw
    readings, ``slot`` the stream slot each fills, ``target`` the plan's target it
    stands for (−1: a slot the plan thinned out), ``angles`` (K, A) rad at mid-window,
    ``smear`` and ``timing`` (K,) rad."""

    index: np.ndarray
    slot: np.ndarray
    target: np.ndarray
    angles: FloatArray
    smear: FloatArray
    timing: FloatArray

    def targets(self) -> Merged:
        """Only the readings that stand for a plan's target (the sweep's samples)."""
        keep = self.target >= 0
        return Merged(
            self.index[keep], self.slot[keep], self.target[keep], self.angles[keep],
            self.smear[keep], self.timing[keep],
        )  # fmt: skip


def target_slots(sweeps: Sweeps, arrival_s: FloatArray, k: int) -> np.ndarray:
    """The stream slots (K,) int64 of sweep ``k``'s targets, in target order: target i's
    is round((arrival_s[i] − cruise_at_s[k]) / period_s), ``arrival_s`` the plan's
    (`Plan.arrival_s`, each target's planned integration start)."""
    first, count = int(sweeps.first[k]), int(sweeps.count[k])
    since = np.asarray(arrival_s[first : first + count], dtype=np.float64)
    since = since - float(sweeps.cruise_at_s[k])
    return np.rint(since / sweeps.period_s).astype(np.int64)


def poll_arrays(polls: list[StampedPositions], axes: tuple[str, ...]) -> tuple[FloatArray, ...]:
    """(P,) request and reply times (s) and (P, A) positions (rad) of ``polls``."""
    request = np.array([p.request_s for p in polls], dtype=np.float64)
    reply = np.array([p.reply_s for p in polls], dtype=np.float64)
    positions = np.array([[p.positions[a] for a in axes] for p in polls], dtype=np.float64)
    return request, reply, positions.reshape(len(polls), len(axes))


def merge(
    request: FloatArray,
    reply: FloatArray,
    positions: FloatArray,
    started: FloatArray,
    ended: FloatArray,
    sweeps: Sweeps,
    k: int,
    slots: np.ndarray | None = None,
    slack_s: float = 0.0,
    window: np.ndarray | None = None,
    velocity: FloatArray | None = None,
) -> Merged:
    """Merge a sweep's polls (request, reply (P,) s; positions (P, A) rad) with its
    readings' windows (started, ended (R,) s) (see the module docstring); ``slots``:
    the stream slots of the sweep's targets (`target_slots`; None: the first ``count``
    slots, a plan streaming its targets only); ``slack_s`` the readings' stamp slack
    (`stamp_slack`), whose /√12 adds to the timing jitter in quadrature; ``window`` the
    readings' window numbers (`window_numbers`; None: their order); ``velocity`` (A,)
    rad/s the axes' as commanded (None: the plan's), the slope of `cruise_offsets`."""
    w = _windows(request, reply, positions, started, ended, slack_s)
    t, first, last = w.t, w.first, w.last
    j = int(np.argmax(np.abs(sweeps.velocity[k])))
    lo, hi = sorted((float(sweeps.entry[k, j]), float(sweeps.exit[k, j])))
    # The stream's phase is the device's: its first or last window may reach up to one
    # period's travel into a ramp (its angles and smear are still measured, by the polls).
    margin = abs(float(sweeps.velocity[k, j])) * sweeps.period_s
    inside = (np.minimum(first[:, j], last[:, j]) >= lo - margin) & (
        np.maximum(first[:, j], last[:, j]) <= hi + margin
    )
    supported = bracketed(t, w.positions[:, j], lo, hi, started, ended, ramp_gap(sweeps, k, j))
    inside &= supported
    slope = np.asarray(sweeps.velocity[k] if velocity is None else velocity, dtype=np.float64)
    offsets = cruise_offsets(t, w.positions, (w.positions[:, j] >= lo) & (w.positions[:, j] <= hi),
                             slope)  # fmt: skip
    if offsets is not None:  # windows in the cruise the polls about them do not support
        a, b = offsets[j] + slope[j] * started, offsets[j] + slope[j] * ended
        on_line = ~supported & (np.minimum(a, b) >= lo - margin) & (np.maximum(a, b) <= hi + margin)
        w = _on_line(w, on_line, offsets, slope, started, ended)
        inside |= on_line
    v = abs(float(slope[j]))  # as commanded: a slot is a time
    along = np.abs(w.angles[:, j] - float(sweeps.entry[k, j])) / v  # s after the entry
    estimate = (along - 0.5 * sweeps.integration_s) / sweeps.period_s  # slot by position
    numbers = np.arange(len(ended)) if window is None else np.asarray(window, dtype=np.int64)
    shift = int(np.rint(np.median(numbers[inside] - estimate[inside]))) if inside.any() else 0
    slot = (numbers - shift).astype(np.int64)
    if slots is None:
        slots = np.arange(int(sweeps.count[k]), dtype=np.int64)
    return _matched(w, slot, inside, slots, sweeps, k)


def cruise_offsets(
    t: FloatArray, positions: FloatArray, cruising: np.ndarray, velocity: FloatArray
) -> FloatArray | None:
    """The axes' angles (A,) rad at time 0 on the lines at ``velocity`` (A,) rad/s
    through the polls (mid-times ``t`` (P,) s, ``positions`` (P, A) rad) that are
    ``cruising`` (P,): the median of each poll's; None with fewer than `CRUISE_POLLS`."""
    if int(np.count_nonzero(cruising)) < CRUISE_POLLS:
        return None
    at_zero = positions[cruising] - t[cruising, None] * velocity[None, :]
    return np.asarray(np.median(at_zero, axis=0), dtype=np.float64)


def _on_line(
    w: _Windows, rows: np.ndarray, offsets: FloatArray, velocity: FloatArray,
    started: FloatArray, ended: FloatArray,
) -> _Windows:  # fmt: skip
    """``w`` with the windows ``rows`` placed on the cruise lines (`cruise_offsets`):
    their angles at the middle, smear |velocity| × the window, timing the steady
    polls' median span / √12 × the speed (the lines' points are polls)."""
    if not rows.any():
        return w
    angles, first, last = w.angles.copy(), w.first.copy(), w.last.copy()
    smear, timing = w.smear.copy(), w.timing.copy()

    def line(times: FloatArray) -> FloatArray:
        return np.asarray(offsets[None, :] + times[:, None] * velocity[None, :])

    s, e = started[rows], ended[rows]
    angles[rows], first[rows], last[rows] = line(0.5 * (s + e)), line(s), line(e)
    speed = float(np.linalg.norm(velocity))
    smear[rows] = speed * (e - s)
    span = float(np.median(w.spans)) if len(w.spans) else 0.0
    timing[rows] = np.hypot(span, w.slack_s) / math.sqrt(12.0) * speed
    return replace(w, angles=angles, first=first, last=last, smear=smear, timing=timing)


def merge_path(
    request: FloatArray,
    reply: FloatArray,
    positions: FloatArray,
    started: FloatArray,
    ended: FloatArray,
    sweeps: Sweeps,
    k: int,
    origin_s: float,
    slots: np.ndarray,
    slack_s: float = 0.0,
    window: np.ndarray | None = None,
) -> Merged:
    """Merge path sweep ``k``'s polls (request, reply (P,) s; positions (P, A) rad) with
    its readings' windows (started, ended (R,) s), the trajectory's origin ``origin_s``
    (s, the clock's); ``slots`` and ``slack_s`` as for `merge`; ``window`` the readings'
    window numbers from the device's timestamps (None without them: each reading's slot
    is then round((started − origin) / period_s), robust to lost lines)."""
    w = _windows(request, reply, positions, started, ended, slack_s)
    t = w.t
    inside = (started >= t[0]) & (ended <= t[-1]) if len(t) >= 2 else np.zeros(len(started), bool)
    estimate = (started - origin_s) / sweeps.period_s
    if window is None:  # no device timestamps: each reading's own stamps (a lost line is
        slot = np.rint(estimate).astype(np.int64)  # no gap in an order-based count)
    else:
        numbers = np.asarray(window, dtype=np.int64)
        shift = int(np.rint(np.median(numbers[inside] - estimate[inside]))) if inside.any() else 0
        slot = (numbers - shift).astype(np.int64)
    return _matched(w, slot, inside, slots, sweeps, k)


@dataclass(frozen=True)
class _Windows:
    """The readings' windows against the polls: the steady polls' mid-times ``t`` (P′,)
    sorted and their ``positions`` (P′, A), each window's angles at its middle, start
    and end (R, A), its ``smear`` and ``timing`` (R,) rad (the module docstring), the
    steady polls' request-to-reply ``spans`` (P′,) s and the readings' ``slack_s``."""

    t: FloatArray
    positions: FloatArray
    angles: FloatArray
    first: FloatArray
    last: FloatArray
    smear: FloatArray
    timing: FloatArray
    spans: FloatArray  # (P′,) s, the steady polls' request-to-reply spans
    slack_s: float


def _windows(
    request: FloatArray, reply: FloatArray, positions: FloatArray, started: FloatArray,
    ended: FloatArray, slack_s: float,
) -> _Windows:  # fmt: skip
    spans = reply - request
    steady = spans <= SLOW_POLL * float(np.median(spans)) if len(spans) else spans > 0
    if steady.sum() < 2:
        steady = np.ones(len(spans), dtype=np.bool_)
    t = 0.5 * (request + reply)[steady]
    order = np.argsort(t, kind="stable")
    t, positions, spans = t[order], positions[steady][order], spans[steady][order]
    middle = 0.5 * (started + ended)

    def at(times: FloatArray) -> FloatArray:
        cols = [np.interp(times, t, positions[:, j]) for j in range(positions.shape[1])]
        return np.stack(cols, axis=1).reshape(len(times), positions.shape[1])

    angles, first, last = at(middle), at(started), at(ended)
    smear = np.linalg.norm(last - first, axis=1)
    span = ended - started
    speed = np.divide(smear, span, out=np.zeros_like(smear), where=span > 0)
    timing = np.hypot(interpolated_span(t, spans, middle), slack_s) / math.sqrt(12.0) * speed
    return _Windows(t, positions, angles, first, last, smear, timing, spans, slack_s)


def _matched(
    w: _Windows, slot: np.ndarray, inside: np.ndarray, slots: np.ndarray, sweeps: Sweeps,
    k: int,
) -> Merged:  # fmt: skip
    """The readings ``inside`` whose ``slot`` is one of the stream's, one a slot, each
    standing for the target whose slot it is (−1: a slot the plan thinned out)."""
    inside = inside & (slot >= 0) & (slot < int(sweeps.streamed[k]))
    _, first_of = np.unique(slot[inside], return_index=True)  # one reading a slot
    index = np.flatnonzero(inside)[np.sort(first_of)].astype(np.int64)
    owner = dict(zip(np.asarray(slots).tolist(), range(len(slots)), strict=True))
    target = np.array(
        [int(sweeps.first[k]) + owner[s] if s in owner else -1 for s in slot[index].tolist()],
        dtype=np.int64,
    )
    return Merged(index, slot[index], target, w.angles[index], w.smear[index], w.timing[index])


def bracketed(
    t: FloatArray, swept: FloatArray, lo: float, hi: float, started: FloatArray,
    ended: FloatArray, ramp_gap_s: float,
) -> np.ndarray:  # fmt: skip
    """Whether each window [started, ended] lies between two polls (mid-times ``t``,
    sorted; never extrapolated) that either are both inside the constant-velocity part
    (``swept`` positions within [lo, hi]: linear motion between them) or are at most
    ``ramp_gap_s`` apart (s; `ramp_gap`: a ramp's curvature between them negligible)."""
    if len(t) < 2:
        return np.zeros(len(started), dtype=np.bool_)
    a = np.searchsorted(t, started, side="right") - 1
    b = np.searchsorted(t, ended, side="left")
    ok = (a >= 0) & (b < len(t))
    a, b = np.clip(a, 0, len(t) - 1), np.clip(b, 0, len(t) - 1)
    cruising = (swept >= lo - 1e-9) & (swept <= hi + 1e-9)
    close = (t[b] - t[a]) <= ramp_gap_s
    return np.asarray(ok & ((cruising[a] & cruising[b]) | close), dtype=np.bool_)


def ramp_gap(sweeps: Sweeps, k: int, j: int) -> float:
    """The longest poll gap (s) across which interpolating sweep ``k``'s swept axis
    ``j`` linearly errs at most `RAMP_BIAS` of a period's travel at its velocity v
    where the gap takes in a ramp: a·g²/8 ≤ RAMP_BIAS·v·period, a = v²/(2 d) the ramp's
    acceleration as planned (d its length, the shorter of the run-up and the overrun)."""
    v = abs(float(sweeps.velocity[k, j]))
    d = min(
        abs(float(sweeps.entry[k, j] - sweeps.start[k, j])),
        abs(float(sweeps.stop[k, j] - sweeps.exit[k, j])),
    )
    if v <= 0.0 or d <= 0.0:
        return 0.0
    return math.sqrt(16.0 * RAMP_BIAS * sweeps.period_s * d / v)


def interpolated_span(t: FloatArray, spans: FloatArray, times: FloatArray) -> FloatArray:
    """The request-to-reply span (s) that interpolating polls at mid-times ``t`` (sorted)
    carries to each of ``times``: sqrt(((1 − w) s₀)² + (w s₁)²) of the two polls about it
    (w its interpolation weight; beyond the ends, the end poll's span)."""
    if not len(t):
        return np.zeros(len(times))
    hi = np.clip(np.searchsorted(t, times), 1, max(len(t) - 1, 1))
    lo = hi - 1
    if len(t) == 1:
        return np.full(len(times), float(spans[0]))
    gap = t[hi] - t[lo]
    w = np.clip(np.divide(times - t[lo], gap, out=np.zeros(len(times)), where=gap > 0), 0, 1)
    return np.asarray(np.hypot((1 - w) * spans[lo], w * spans[hi]), dtype=np.float64)


def window_numbers(device_t: list[float | None], period_s: float) -> np.ndarray:
    """The readings' window numbers (R,) int64 from the first: from the device's
    timestamps (s) when each has one (a lost line leaves a gap), else their order."""
    if not device_t or any(t is None for t in device_t):
        return np.arange(len(device_t), dtype=np.int64)
    t = np.array(device_t, dtype=np.float64)
    return np.asarray(np.rint((t - t[0]) / period_s), dtype=np.int64)


def stamp_slack(readings: list[StreamReading]) -> float:
    """The width (s) of the span the stream's windows are known to have ended in, one
    offset for all: the smallest ``received_s − earliest_end_s`` of the readings (a line
    cannot arrive before its window ends, nor a window end before the bound its driver
    states), or of ``received_s − ended_s`` where no bound is stated; 0 without arrival
    times. The stamps lie in that span: on a host slow to read every line (a loaded
    one), the fastest line's arrival may still lie well after its window's end, and
    the span says by how much at most."""
    late = [
        r.received_s - (r.ended_s if r.earliest_end_s is None else r.earliest_end_s)
        for r in readings
        if r.received_s is not None
    ]
    return max(0.0, min(late)) if late else 0.0


@dataclass(frozen=True)
class Derived:
    """A sweep's raw streams as arrays (`poll_arrays`; the readings' windows, s), every
    matched reading (`merge`), the samples (the matched readings standing for targets)
    and each sample's added counts σ (`angular_sigma`, its slope taken over every
    matched reading)."""

    request: FloatArray
    reply: FloatArray
    positions: FloatArray
    started: FloatArray
    ended: FloatArray
    matched: Merged
    samples: Merged
    extra: FloatArray


def derive(
    raw: RawSweep, axes: tuple[str, ...], sweeps: Sweeps, arrival_s: FloatArray, k: int
) -> Derived:
    """Sweep ``k``'s samples from its raw streams (``arrival_s``: the plan's)."""
    request, reply, positions = poll_arrays(raw.polls, axes)
    started = np.array([r.started_s for r in raw.readings], dtype=np.float64)
    ended = np.array([r.ended_s for r in raw.readings], dtype=np.float64)
    slots = target_slots(sweeps, arrival_s, k)
    slack = stamp_slack(raw.readings)
    window = window_numbers([r.device_t_s for r in raw.readings], sweeps.period_s)
    if raw.origin_s is not None:
        stamped = all(r.device_t_s is not None for r in raw.readings)
        matched = merge_path(request, reply, positions, started, ended, sweeps, k, raw.origin_s,
                             slots, slack, window if stamped else None)  # fmt: skip
    else:
        velocity = np.asarray(sweeps.velocity[k], dtype=np.float64)
        if raw.velocities is not None:  # the register's steps, the plan's signs
            pairs = zip(axes, velocity.tolist(), strict=True)
            commanded = [raw.velocities.get(a, abs(v)) for a, v in pairs]
            velocity = np.copysign(np.asarray(commanded, dtype=np.float64), velocity)
        matched = merge(request, reply, positions, started, ended, sweeps, k, slots, slack,
                        window, velocity)  # fmt: skip
    counts = np.array([raw.readings[r].value for r in matched.index.tolist()], dtype=np.float64)
    extra = angular_sigma(counts, matched.angles, matched.smear, matched.timing)
    return Derived(
        request, reply, positions, started, ended, matched, matched.targets(),
        extra[matched.target >= 0],
    )  # fmt: skip


def angular_sigma(counts: FloatArray, angles: FloatArray, smear: FloatArray, timing: FloatArray
                  ) -> FloatArray:  # fmt: skip
    """The counts' standard deviation (K,) that the angular uncertainty of each kept
    reading adds: |d counts / d path| (finite differences along the sweep) × the angular
    σ, sqrt(timing² + smear² / 12) (a uniform smear over the window)."""
    if len(counts) < 2:
        return np.zeros(len(counts))
    path = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(angles, axis=0), axis=1))])
    if not np.all(np.diff(path) > 0):
        return np.zeros(len(counts))
    slope = np.abs(np.gradient(counts, path))
    return np.asarray(slope * np.sqrt(timing**2 + smear**2 / 12.0))
