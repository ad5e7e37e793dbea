"""The speed-versus-accuracy trade, measured: sweeps of plan → simulated acquisition →
reconstruction → evaluation over the axes of a sweep file (docs/explanations/tradeoff.md).

`grid.load_sweep` reads a sweep file into tasks, `runner.run` turns one task into a
results row, `sweep.run_sweep` runs the missing ones (here, on a local pool or on Dask:
`executors`) into an output folder (`store`) and writes the report (`report`, `plots`,
`front`, `target`). `choice.choose` picks the plan for a time budget and a material
guess: every candidate fitted to the budget, its error predicted by one model.
"""

from gonio.tradeoff.choice import TEST_PAIRS, Choice, choose, material_guess
from gonio.tradeoff.grid import Sweep, load_sweep
from gonio.tradeoff.sweep import SweepResult, run_sweep

__all__ = [
    "TEST_PAIRS",
    "Choice",
    "Sweep",
    "SweepResult",
    "choose",
    "load_sweep",
    "material_guess",
    "run_sweep",
]
