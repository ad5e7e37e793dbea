"""The sampling planner: plan file → points uniform in a parametrization's coordinates →
reachable direction pairs → joint angles → an ordered, timed `Plan`. See docs/planner.md."""

from gonio.planner.plan import Plan, Summary, build, load_plan, render_summary

__all__ = ["Plan", "Summary", "build", "load_plan", "render_summary"]
