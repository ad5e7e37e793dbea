"""The sampling planner: plan file → points uniform in a parametrization's coordinates →
reachable direction pairs → joint angles → an ordered, timed `Plan`, stored and read
back bit for bit (`write_plan`, `read_plan`). See docs/reference/planner.md.

Modules: `model` (the `Plan`, its `Summary`, the hashes), `builder` (`build`), `files`
(plan files), `stored` (stored plans), `two_pass` (the adaptive strategy's second pass),
`choice` (whether that pass adapts, decided from the survey). The names below load with
their module when first used (`gonio.faces`): reading a stored plan builds nothing."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.planner import adaptive as adaptive
    from gonio.planner import lkh as lkh
    from gonio.planner.blur import BLUR_K_DEG as BLUR_K_DEG
    from gonio.planner.blur import blur_budget_deg as blur_budget_deg
    from gonio.planner.blur import blur_budget_of_width as blur_budget_of_width
    from gonio.planner.builder import build as build
    from gonio.planner.choice import MARGIN as MARGIN
    from gonio.planner.choice import Choice as Choice
    from gonio.planner.files import PlanSource as PlanSource
    from gonio.planner.files import load_plan as load_plan
    from gonio.planner.files import load_plan_source as load_plan_source
    from gonio.planner.fly.limits import blur_floor_deg as blur_floor_deg
    from gonio.planner.fly_spec import MIN_BLUR_DEG as MIN_BLUR_DEG
    from gonio.planner.fly_spec import MIN_RATE_HZ as MIN_RATE_HZ
    from gonio.planner.fly_spec import FlySpec as FlySpec
    from gonio.planner.model import ARRAYS as ARRAYS
    from gonio.planner.model import Plan as Plan
    from gonio.planner.model import Summary as Summary
    from gonio.planner.model import Sweeps as Sweeps
    from gonio.planner.model import content_hash as content_hash
    from gonio.planner.model import sha256 as sha256
    from gonio.planner.ordering import compile_kernels as compile_kernels
    from gonio.planner.ordering import default_kicks as default_kicks
    from gonio.planner.placement import directions as directions
    from gonio.planner.placement import draw_kept as draw_kept
    from gonio.planner.placement import place as place
    from gonio.planner.policies import AcquisitionSpec as AcquisitionSpec
    from gonio.planner.policies import HealthSpec as HealthSpec
    from gonio.planner.policies import MotorFaultSpec as MotorFaultSpec
    from gonio.planner.schema import MAX_KICKS_GIVEN as MAX_KICKS_GIVEN
    from gonio.planner.schema import MAX_MOVES as MAX_MOVES
    from gonio.planner.schema import MAX_PLAN_MINUTES as MAX_PLAN_MINUTES
    from gonio.planner.schema import MAX_TARGETS as MAX_TARGETS
    from gonio.planner.schema import WHY_MAX_TARGETS as WHY_MAX_TARGETS
    from gonio.planner.schema import AdaptiveSpec as AdaptiveSpec
    from gonio.planner.schema import ExposureSpec as ExposureSpec
    from gonio.planner.schema import PlanSpec as PlanSpec
    from gonio.planner.schema import Strategy as Strategy
    from gonio.planner.schema import Warp as Warp
    from gonio.planner.search import path_time as path_time
    from gonio.planner.stored import parse_plan as parse_plan
    from gonio.planner.stored import plan_bytes as plan_bytes
    from gonio.planner.stored import read_plan as read_plan
    from gonio.planner.stored import write_plan as write_plan
    from gonio.planner.two_pass import Survey as Survey
    from gonio.planner.two_pass import draw_points as draw_points
    from gonio.planner.two_pass import extend as extend
    from gonio.planner.two_pass import second_pass as second_pass

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "ARRAYS": "model",
    "AcquisitionSpec": "policies",
    "AdaptiveSpec": "schema",
    "BLUR_K_DEG": "blur",
    "Choice": "choice",
    "ExposureSpec": "schema",
    "FlySpec": "fly_spec",
    "HealthSpec": "policies",
    "MARGIN": "choice",
    "MAX_KICKS_GIVEN": "schema",
    "MAX_MOVES": "schema",
    "MAX_PLAN_MINUTES": "schema",
    "MAX_TARGETS": "schema",
    "MIN_BLUR_DEG": "fly_spec",
    "MIN_RATE_HZ": "fly_spec",
    "MotorFaultSpec": "policies",
    "Plan": "model",
    "PlanSource": "files",
    "PlanSpec": "schema",
    "Strategy": "schema",
    "Summary": "model",
    "Survey": "two_pass",
    "Sweeps": "model",
    "WHY_MAX_TARGETS": "schema",
    "Warp": "schema",
    "adaptive": "adaptive",
    "blur_budget_deg": "blur",
    "blur_budget_of_width": "blur",
    "blur_floor_deg": "fly.limits",
    "build": "builder",
    "compile_kernels": "ordering",
    "content_hash": "model",
    "default_kicks": "ordering",
    "directions": "placement",
    "draw_kept": "placement",
    "draw_points": "two_pass",
    "extend": "two_pass",
    "lkh": "lkh",
    "load_plan": "files",
    "load_plan_source": "files",
    "parse_plan": "stored",
    "path_time": "search",
    "place": "placement",
    "plan_bytes": "stored",
    "read_plan": "stored",
    "second_pass": "two_pass",
    "sha256": "model",
    "write_plan": "stored",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
