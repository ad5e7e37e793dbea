"""A run's calibrated samples: raw counts → BRDF values and their uncertainty through
the journaled calibration readings (`calibrate`), the samples as a measurement
(`Measured`), the calibration error they share (`shared_error`), the run's figures
and, for a simulated run, the truth it measured (read from the stored scene, without
the simulator), and a run re-derived with a later alignment (`realigned`).
"""

from typing import TYPE_CHECKING

from gonio.analysis.calibrated import Calibrated, calibrate, calibration_series
from gonio.analysis.measured import Measured, kept
from gonio.analysis.realign import realigned
from gonio.analysis.shared import SharedError, shared_error
from gonio.analysis.summary import error_figures, figures, measured_pairs, truth_of
from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.analysis import summary as summary
    from gonio.analysis.calibrated import is_level as is_level

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "is_level": "calibrated",
    "summary": "summary",
}
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
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
