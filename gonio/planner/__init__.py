"""The sampling planner: plan file → points uniform in a parametrization's coordinates →
reachable direction pairs → joint angles → an ordered, timed `Plan`, stored and read
back bit for bit (`Plan.write`, `read_plan`). See docs/planner.md."""

from gonio.planner.plan import (
    Plan,
    PlanSource,
    Summary,
    build,
    content_hash,
    load_plan,
    load_plan_source,
    render_summary,
)
from gonio.planner.stored import read_plan

__all__ = [
    "Plan",
    "PlanSource",
    "Summary",
    "build",
    "content_hash",
    "load_plan",
    "load_plan_source",
    "read_plan",
    "render_summary",
]
