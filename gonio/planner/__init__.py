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
    from gonio.planner.builder import build as build
    from gonio.planner.files import (
        PlanSource as PlanSource,
    )
    from gonio.planner.files import (
        load_plan as load_plan,
    )
    from gonio.planner.files import (
        load_plan_source as load_plan_source,
    )
    from gonio.planner.model import (
        Plan as Plan,
    )
    from gonio.planner.model import (
        Summary as Summary,
    )
    from gonio.planner.model import (
        content_hash as content_hash,
    )
    from gonio.planner.model import (
        sha256 as sha256,
    )
    from gonio.planner.stored import (
        parse_plan as parse_plan,
    )
    from gonio.planner.stored import (
        plan_bytes as plan_bytes,
    )
    from gonio.planner.stored import (
        read_plan as read_plan,
    )
    from gonio.planner.stored import (
        write_plan as write_plan,
    )

#: Each name of the face, by the module that defines it.
WHERE = {
    "Plan": "model",
    "PlanSource": "files",
    "Summary": "model",
    "build": "builder",
    "content_hash": "model",
    "load_plan": "files",
    "load_plan_source": "files",
    "parse_plan": "stored",
    "plan_bytes": "stored",
    "read_plan": "stored",
    "sha256": "model",
    "write_plan": "stored",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
