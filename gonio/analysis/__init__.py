"""A run's calibrated samples: raw counts → BRDF values and their uncertainty through
the journaled calibration readings (`calibrate`), the samples as a measurement
(`Measured`), the calibration error they share (`shared_error`), the run's figures
and, for a simulated run, the truth it measured (read from the stored scene, without
the simulator), and a run re-derived with a later alignment (`realigned`).
"""

from gonio.analysis.calibrated import Calibrated, calibrate, calibration_series
from gonio.analysis.measured import Measured, kept
from gonio.analysis.realign import realigned
from gonio.analysis.shared import SharedError, shared_error
from gonio.analysis.summary import error_figures, figures, measured_pairs, truth_of

__all__ = [
    "Calibrated",
    "Measured",
    "SharedError",
    "calibrate",
    "calibration_series",
    "error_figures",
    "figures",
    "kept",
    "measured_pairs",
    "realigned",
    "shared_error",
    "truth_of",
]
