"""The sampling planner: plan file → points uniform in a parametrization's coordinates →
reachable direction pairs → joint angles → an ordered, timed `Plan`, stored and read
back bit for bit (`write_plan`, `read_plan`). See docs/reference/planner.md.

Modules: `model` (the `Plan`, its `Summary`, the hashes), `builder` (`build`), `files`
(plan files and stored plans), `two_pass` (the adaptive strategy's second pass), `choice`
(whether that pass adapts, decided from the survey)."""

from gonio.planner.builder import build
from gonio.planner.files import (
    PlanSource,
    load_plan,
    load_plan_source,
    parse_plan,
    plan_bytes,
    read_plan,
    write_plan,
)
from gonio.planner.model import Plan, Summary, content_hash, sha256

__all__ = [
    "Plan",
    "PlanSource",
    "Summary",
    "build",
    "content_hash",
    "load_plan",
    "load_plan_source",
    "parse_plan",
    "plan_bytes",
    "read_plan",
    "sha256",
    "write_plan",
]
