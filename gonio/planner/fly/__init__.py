"""Fly plans: readings taken while one axis sweeps at constant velocity.

Modules: `lines` (the segments, their velocity from the blur budget), `thin` (the
streamed readings thinned to the target density), `coverage` (how the readings cover the
reach), `build` (`build_fly`: the layout, its order and timing), `limits` (what a plan may ask
of the rig and this machine, checked first); path lines along θh
that every axis follows: `paths` (a line's segments, time law, trajectory and readings)
and `path_plan` (`build_paths`: their layout, order and timing).
"""

from gonio.planner.fly.build import build_fly
from gonio.planner.fly.lines import sweep_axis
from gonio.planner.fly.path_plan import build_paths
from gonio.planner.fly.thin import THINNED

__all__ = ["THINNED", "build_fly", "build_paths", "sweep_axis"]
