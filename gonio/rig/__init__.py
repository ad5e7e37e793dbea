"""Rig description and kinematics: the rig file (with the instrument's light, detector
and reference standard, `gonio.rig.instrument`), forward kinematics of any chain of
revolute axes, closed-form inverse kinematics of the shipped rig types, the physical
constraints (``Reason``) and the axes' travel-time model. See docs/reference/planner.md."""

from gonio.rig.model import Reason, Rig, Solution
from gonio.rig.travel import TravelModel

__all__ = ["Reason", "Rig", "Solution", "TravelModel"]
