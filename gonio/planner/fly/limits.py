"""What a fly plan may ask of the rig and of this machine, checked before it is laid out.

- Integration: within the detector's exposure range (the rig file's
  ``detector.exposure_range_s``).
- Blur: at least the quantization of the axes that sweep (one encoder tick / √12,
  `gonio.rig.sensitivity.axis_errors`): a reading's pose is known no better, so a smaller
  smear buys no accuracy (`blur_floor_deg`).
- Memory: the readings asked (``sampling.target``) times `BYTES_PER_READING` within the
  memory this machine has available (`available_bytes`).
- Time: the planning time estimated from the readings and the sweeps they need
  (`planning_estimate`) within `MAX_PLANNING_S`.

Each is one `ConfigError` line naming the field, before anything is allocated.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from gonio.config import ConfigError
from gonio.planner.fly.lines import sweep_axis
from gonio.planner.fly_spec import FlySpec
from gonio.planner.schema import PlanSpec
from gonio.rig import Rig, axis_errors

#: Peak memory (bytes) of planning per reading asked: at most 0.7 KB measured on the
#: shipped arcs and θh lines at 200 000 readings (the streamed readings the thinning or
#: the line step leave out included), with a margin for plans that stream more per kept
#: reading.
BYTES_PER_READING = 2048
#: Planning time per reading laid out and per sweep line (s), measured on the shipped
#: plans (the layout, thinning, ordering and coverage figures; a line's commandable
#: poses and rates on its fine grid).
SECONDS_PER_READING = 0.125e-3
SECONDS_PER_LINE = 0.01
#: The longest planning a fly plan may ask for (s): the shipped plans of a million
#: readings plan within it; a longer one is hours of a planner that prints nothing.
MAX_PLANNING_S = 600.0
#: Readings laid out per reading asked (the thinning keeps about half the stream).
LAID_PER_READING = 2.0
#: Share of a line's streamed readings that are kept (the thinning, the reach).
KEPT_PER_LINE = 0.5
#: θh span of a path line (rad): from the mirror direction to grazing.
LINE_SPAN = 0.5 * math.pi


def available_bytes() -> int:
    """The memory this machine has available (bytes): ``MemAvailable`` of
    /proc/meminfo where there is one, else the physical memory."""
    try:
        for line in Path("/proc/meminfo").read_text(encoding="ascii").splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))


def blur_floor_deg(rig: Rig, fly: FlySpec) -> tuple[float, str]:
    """(the smallest blur budget (°) worth asking on ``rig``, the axis it comes from): the
    quantization (tick / √12) of the swept axis, or of the coarsest axis for lines
    along θh, which every axis follows."""
    quantization = axis_errors(rig).quantization
    j = int(quantization.argmax()) if fly.segment == "theta_h_line" else sweep_axis(rig, fly)
    return math.degrees(float(quantization[j])), rig.axes[j]


@dataclass(frozen=True)
class Estimate:
    """A fly plan's planning cost, estimated before it is laid out."""

    readings: int  # readings asked
    per_line: float  # readings a sweep line keeps, at most
    lines: int  # lines laid out, at least
    seconds: float  # planning time
    bytes: int  # peak memory


def planning_estimate(spec: PlanSpec, rig: Rig) -> Estimate:
    """The planning cost of ``spec`` on ``rig``: the readings a line keeps at most (its
    span over the readings' spacing, the sweep at its fastest: blur / integration, at
    most the axis's velocity, for a unit angular rate of the directions), so the lines
    at least, their time (`SECONDS_PER_LINE`) and the readings' (`SECONDS_PER_READING`,
    `LAID_PER_READING` laid per reading asked) and their memory
    (`BYTES_PER_READING`)."""
    fly = spec.sampling.fly_options()
    target = spec.sampling.target or 0
    blur, t_int = math.radians(fly.blur), fly.integration
    if fly.segment == "theta_h_line":
        v = min(blur / t_int, float(rig.velocity.max()))
        per_line = max(LINE_SPAN / max(v * fly.period_s, 0.5 * blur), 1.0)
    else:
        j = sweep_axis(rig, fly)
        v = min(blur / t_int, float(rig.velocity[j]))
        span = float(rig.limits[j, 1] - rig.limits[j, 0])
        per_line = KEPT_PER_LINE * max(span / (v * fly.period_s), 1.0)
    lines = math.ceil(target / per_line)
    seconds = lines * SECONDS_PER_LINE + LAID_PER_READING * target * SECONDS_PER_READING
    return Estimate(target, per_line, lines, seconds, target * BYTES_PER_READING)


def check_fly(spec: PlanSpec, rig: Rig, where: str) -> None:
    """`ConfigError` (one line) unless the fly plan ``spec`` can be laid out on ``rig``
    on this machine (the module docstring), before anything is allocated."""
    fly = spec.sampling.fly_options()
    lo, hi = rig.spec.detector.exposure_range_s
    t = fly.integration
    if not lo <= t <= hi:
        raise ConfigError(
            f"{where}: sampling.fly.integration_s: {t:g} s is outside the detector's exposure "
            f"range [{lo:g}, {hi:g}] s (the rig file's detector.exposure_range_s)"
        )
    floor, axis = blur_floor_deg(rig, fly)
    if fly.blur < floor:
        field = "blur_deg" if fly.blur_deg is not None else "lobe_width_deg"
        raise ConfigError(
            f"{where}: sampling.fly.{field}: expected a blur budget of at least {floor:.3g}° "
            f"(the quantization of {axis}'s encoder, one tick / √12: a reading's pose is "
            f"known no better), got {fly.blur:.3g}°"
        )
    cost = planning_estimate(spec, rig)
    have = available_bytes()
    if cost.bytes > have:
        raise ConfigError(
            f"{where}: sampling.target: {cost.readings:,} readings need about "
            f"{_size(cost.bytes)} of memory to plan; this machine has {_size(have)} available "
            f"(expected at most {have // BYTES_PER_READING:,} readings)"
        )
    if cost.seconds > MAX_PLANNING_S:
        most = int(cost.readings * MAX_PLANNING_S / cost.seconds)
        raise ConfigError(
            f"{where}: sampling.target: {cost.readings:,} readings on at least {cost.lines:,} "
            f"sweeps of at most {cost.per_line:,.0f} kept readings would take about "
            f"{cost.seconds / 60:,.0f} min to plan; expected at most {MAX_PLANNING_S / 60:g} "
            f"min (at most {most:,} readings here, or fewer, longer sweeps: a higher "
            "rate_hz or a longer integration_s)"
        )


def _size(count: int) -> str:
    """A byte count as a person reads it (1.5 GiB)."""
    size = float(count)
    for unit in ("B", "KiB", "MiB", "GiB"):
        if size < 1024:
            return f"{size:.1f} {unit}" if unit != "B" else f"{count} B"
        size /= 1024
    return f"{size:.1f} TiB"
