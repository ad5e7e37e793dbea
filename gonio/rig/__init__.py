"""Rig description and kinematics: the rig file (with the instrument's light, detector
and reference standard, `gonio.rig.instrument`), forward kinematics of any chain of
revolute axes, closed-form inverse kinematics of the shipped rig types, the physical
constraints (``Reason``), the axes' travel-time model, and a rig's misalignment
(`Alignment`, applied by the forward kinematics). See docs/reference/planner.md."""

from gonio.rig.alignment import Alignment, Geometry
from gonio.rig.alignment_spec import AlignmentSpec
from gonio.rig.model import Rig
from gonio.rig.solution import Reason, Solution
from gonio.rig.travel import TravelModel

__all__ = ["Alignment", "AlignmentSpec", "Geometry", "Reason", "Rig", "Solution", "TravelModel"]
