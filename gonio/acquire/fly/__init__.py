"""Fly acquisition: a fly plan's sweeps measured on the devices (`run_sweep`), their
streams merged into samples with no device I/O (`merge`, `derive`), and the engine's
loop over them (`FlyLoop`, seeing the engine through a `FlyContext`).

Modules: `merge` (pure estimation), `run` (device I/O), `loop` (the fly loop).
"""

from gonio.acquire.fly.loop import FlyContext, FlyLoop
from gonio.acquire.fly.merge import (
    Derived,
    Merged,
    RawSweep,
    angular_sigma,
    bracketed,
    derive,
    interpolated_span,
    merge,
    merge_path,
    poll_arrays,
    ramp_gap,
    stamp_slack,
    target_slots,
    window_numbers,
)
from gonio.acquire.fly.run import run_path_sweep, run_sweep

__all__ = [
    "Derived",
    "FlyContext",
    "FlyLoop",
    "Merged",
    "RawSweep",
    "angular_sigma",
    "bracketed",
    "derive",
    "interpolated_span",
    "merge",
    "merge_path",
    "poll_arrays",
    "ramp_gap",
    "run_path_sweep",
    "run_sweep",
    "stamp_slack",
    "target_slots",
    "window_numbers",
]
