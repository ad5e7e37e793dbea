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

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.tradeoff import runner as runner
    from gonio.tradeoff.choice import TEST_PAIRS as TEST_PAIRS
    from gonio.tradeoff.choice import Choice as Choice
    from gonio.tradeoff.choice import Prediction as Prediction
    from gonio.tradeoff.choice import choose as choose
    from gonio.tradeoff.choice import material_guess as material_guess
    from gonio.tradeoff.executors import check_address as check_address
    from gonio.tradeoff.grid import Sweep as Sweep
    from gonio.tradeoff.grid import load_sweep as load_sweep
    from gonio.tradeoff.grid import scaled_rig as scaled_rig
    from gonio.tradeoff.spec import EFFECT_NAMES as EFFECT_NAMES
    from gonio.tradeoff.spec import SweepSpec as SweepSpec
    from gonio.tradeoff.store import open_store as open_store
    from gonio.tradeoff.sweep import SweepResult as SweepResult
    from gonio.tradeoff.sweep import run_sweep as run_sweep

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Choice": "choice",
    "EFFECT_NAMES": "spec",
    "Prediction": "choice",
    "Sweep": "grid",
    "SweepResult": "sweep",
    "SweepSpec": "spec",
    "TEST_PAIRS": "choice",
    "check_address": "executors",
    "choose": "choice",
    "load_sweep": "grid",
    "material_guess": "choice",
    "open_store": "store",
    "run_sweep": "sweep",
    "runner": "runner",
    "scaled_rig": "grid",
}
__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
