"""The speed-versus-accuracy trade, measured: sweeps of plan → simulated acquisition →
reconstruction → evaluation over the axes of a sweep file (docs/explanations/tradeoff.md).

`grid.load_sweep` reads a sweep file into tasks, `runner.run` turns one task into a
results row, `sweep.run_sweep` runs the missing ones (here, on a local pool or on Dask:
`executors`) into an output folder (`store`) and writes the report (`report`, `plots`,
`front`, `target`). `choice.choose` picks the plan for a time budget and a material
guess: every candidate fitted to the budget, its error predicted by one model.
"""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.tradeoff.choice import TEST_PAIRS, Choice, choose, material_guess
from gonio.tradeoff.grid import Sweep, load_sweep
from gonio.tradeoff.sweep import SweepResult, run_sweep

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.tradeoff import runner as runner
    from gonio.tradeoff.choice import Prediction as Prediction
    from gonio.tradeoff.executors import check_address as check_address
    from gonio.tradeoff.grid import scaled_rig as scaled_rig
    from gonio.tradeoff.spec import EFFECT_NAMES as EFFECT_NAMES
    from gonio.tradeoff.spec import SweepSpec as SweepSpec
    from gonio.tradeoff.store import open_store as open_store

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "EFFECT_NAMES": "spec",
    "Prediction": "choice",
    "SweepSpec": "spec",
    "check_address": "executors",
    "open_store": "store",
    "runner": "runner",
    "scaled_rig": "grid",
}
__all__ = [
    "Choice",
    "Sweep",
    "SweepResult",
    "TEST_PAIRS",
    "choose",
    "load_sweep",
    "material_guess",
    "run_sweep",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
