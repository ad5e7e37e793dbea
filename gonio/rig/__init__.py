"""Rig description and kinematics: the rig file (with the instrument's light, detector
and reference standard, `gonio.rig.instrument`), forward kinematics of any chain of
revolute axes, closed-form inverse kinematics of the shipped rig types, the physical
constraints (``Reason``), the axes' travel-time model, and a rig's misalignment
(`Alignment`, applied by the forward kinematics). See docs/reference/planner.md."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face
from gonio.rig.alignment import Alignment, Geometry
from gonio.rig.alignment_spec import AlignmentSpec
from gonio.rig.model import Rig
from gonio.rig.solution import Reason, Solution
from gonio.rig.travel import TravelModel

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.rig import constraints as constraints
    from gonio.rig import sensitivity as sensitivity
    from gonio.rig.alignment_file import AlignmentFile as AlignmentFile
    from gonio.rig.alignment_file import from_fit as from_fit
    from gonio.rig.alignment_file import load_alignment as load_alignment
    from gonio.rig.alignment_file import text as text
    from gonio.rig.alignment_fit import as_alignment as as_alignment
    from gonio.rig.alignment_fit import fit as fit
    from gonio.rig.alignment_fit import miss as miss
    from gonio.rig.alignment_fit import parameters as parameters
    from gonio.rig.alignment_fit import peak_at as peak_at
    from gonio.rig.alignment_fit import stated_covariance as stated_covariance
    from gonio.rig.alignment_fit import vector as vector
    from gonio.rig.constraints import footprint_ok as footprint_ok
    from gonio.rig.constraints import separation as separation
    from gonio.rig.constraints import view_on_sample as view_on_sample
    from gonio.rig.instrument import SerialInterfaceSpec as SerialInterfaceSpec
    from gonio.rig.instrument import SerialSwitchSpec as SerialSwitchSpec
    from gonio.rig.lab_instrument import PyMeasureInterfaceSpec as PyMeasureInterfaceSpec
    from gonio.rig.model import named_alignment as named_alignment
    from gonio.rig.refusals import Refusals as Refusals
    from gonio.rig.schema import JOINT_LIMIT_DEG as JOINT_LIMIT_DEG
    from gonio.rig.schema import HealthLimitsSpec as HealthLimitsSpec
    from gonio.rig.schema import RigSpec as RigSpec
    from gonio.rig.sensitivity import alignment_brdf_sigma as alignment_brdf_sigma
    from gonio.rig.sensitivity import axis_errors as axis_errors

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "Refusals": "refusals",
    "AlignmentFile": "alignment_file",
    "HealthLimitsSpec": "schema",
    "JOINT_LIMIT_DEG": "schema",
    "PyMeasureInterfaceSpec": "lab_instrument",
    "RigSpec": "schema",
    "SerialInterfaceSpec": "instrument",
    "SerialSwitchSpec": "instrument",
    "alignment_brdf_sigma": "sensitivity",
    "as_alignment": "alignment_fit",
    "axis_errors": "sensitivity",
    "constraints": "constraints",
    "fit": "alignment_fit",
    "footprint_ok": "constraints",
    "from_fit": "alignment_file",
    "load_alignment": "alignment_file",
    "miss": "alignment_fit",
    "named_alignment": "model",
    "parameters": "alignment_fit",
    "peak_at": "alignment_fit",
    "sensitivity": "sensitivity",
    "separation": "constraints",
    "stated_covariance": "alignment_fit",
    "text": "alignment_file",
    "vector": "alignment_fit",
    "view_on_sample": "constraints",
}
__all__ = [
    "Alignment",
    "AlignmentSpec",
    "Geometry",
    "Reason",
    "Rig",
    "Solution",
    "TravelModel",
    *WHERE,
]
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
