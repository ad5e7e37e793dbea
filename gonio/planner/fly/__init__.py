"""Fly plans: readings taken while one axis sweeps at constant velocity.

Modules: `lines` (the segments, their velocity from the blur budget), `thin` (the
streamed readings thinned to the target density), `coverage` (how the readings cover the
reach), `build` (`build_fly`: the layout, its order and timing), `limits` (what a plan may ask
of the rig and this machine, checked first); path lines along θh
that every axis follows: `paths` (a line's segments, time law, trajectory and readings)
and `path_plan` (`build_paths`: their layout, order and timing).
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.planner.fly.build import build_fly as build_fly
    from gonio.planner.fly.lines import sweep_axis as sweep_axis
    from gonio.planner.fly.path_plan import build_paths as build_paths
    from gonio.planner.fly.thin import THINNED as THINNED

#: The names of the face that load with their module when first used (`gonio.faces`):
#: checking a plan's limits (`limits`) loads no builder (scipy, numba).
WHERE = {
    "THINNED": "thin",
    "build_fly": "build",
    "build_paths": "path_plan",
    "sweep_axis": "lines",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
